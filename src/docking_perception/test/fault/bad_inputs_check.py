#!/usr/bin/env python3
"""Issue 12 items 1-3 end to end (sim time): the simulator renders a still target 1.5 m ahead, the
guidance chain (perception.launch, the arbiter, the planner) runs on it, and this node publishes
malformed inputs beside the real ones:

- on every camera's image_raw: encoding "foo", 0x0, truncated mono8, step too small, huge dimensions
  with little data, no frame_id, a stamp 1000 s ahead;
- on every camera's camera_info: 1 x 100000 px, NaN in K, an unknown distortion model, R all zero, a
  stamp 1000 s ahead;
- on every estimator topic and on target/estimate: a stamp 1000 s ahead, a zero quaternion with
  orientation_valid, NaNs, each carrying a marker range (7.77 m) no real estimate has;
- on odom: a position 1e30 m away, a zero quaternion, a stamp 1000 s ahead.

It asserts that no process died (the perception manager, the arbiter and the planner answer pings),
that valid FUSED estimates keep flowing from the real estimators afterwards, that no output carries the
marker or a non-unit orientation, that the planner still sees the target, and that the diagnostics of
the image guards, the arbiter and the planner name this node as the publisher of what they dropped and
count each kind by its code.
"""
import math
import threading
import time
import unittest

import rosnode
import rospy
import rostest
from diagnostic_msgs.msg import DiagnosticArray
from docking_msgs.msg import DockingState, TargetEstimate
from nav_msgs.msg import Odometry
from sensor_msgs.msg import CameraInfo, Image

PKG = "docking_perception"
MARKER_RANGE_M = 7.77  # the injected estimates' range: no real one is there
CAMERAS = ["stereo/left", "stereo/right", "ir"]
CAMERA_FRAMES = {"stereo/left": "stereo_left_optical_frame", "stereo/right": "stereo_right_optical_frame",
                 "ir": "ir_optical_frame"}
ESTIMATE_TOPICS = {"perception/disparity/estimate": TargetEstimate.SOURCE_DISPARITY,
                   "perception/mono_visible/estimate": TargetEstimate.SOURCE_MONO_VISIBLE,
                   "perception/mono_ir/estimate": TargetEstimate.SOURCE_MONO_IR,
                   "target/estimate": TargetEstimate.SOURCE_FUSED}


def rotated(items, k):
    """items, starting at index k (mod its length)."""
    k %= len(items)
    return items[k:] + items[:k]


def malformed_images(frame_id, now):
    """(code the guard must give, Image) for each malformed kind."""
    def image(encoding, width, height, step, size, frame=frame_id, stamp=now):
        msg = Image()
        msg.header.stamp = stamp
        msg.header.frame_id = frame
        msg.encoding, msg.width, msg.height, msg.step = encoding, width, height, step
        msg.data = bytes(size)
        return msg
    return [
        ("unknown_encoding", image("foo", 64, 48, 64, 64 * 48)),
        ("zero_size", image("mono8", 0, 0, 0, 0)),
        ("data_size_mismatch", image("mono8", 640, 480, 640, 640 * 100)),        # truncated
        ("step_too_small", image("bgr8", 64, 48, 64, 64 * 48)),
        ("too_large", image("mono8", 100000, 100000, 100000, 1000)),            # huge, little data
        ("no_frame_id", image("mono8", 64, 48, 64, 64 * 48, frame="")),
        ("stamp_in_future", image("mono8", 64, 48, 64, 64 * 48, stamp=now + rospy.Duration(1000.0))),
    ]


def malformed_camera_infos(frame_id, now):
    """(code the guard must give, CameraInfo) for each malformed kind; each otherwise a 640 x 480 camera."""
    def info(stamp=now):
        msg = CameraInfo()
        msg.header.stamp = stamp
        msg.header.frame_id = frame_id
        msg.width, msg.height = 640, 480
        msg.distortion_model = "plumb_bob"
        msg.D = [0.0] * 5
        msg.K = [500.0, 0.0, 320.0, 0.0, 500.0, 240.0, 0.0, 0.0, 1.0]
        msg.R = [1.0, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 1.0]
        msg.P = [500.0, 0.0, 320.0, 0.0, 0.0, 500.0, 240.0, 0.0, 0.0, 0.0, 1.0, 0.0]
        return msg
    too_large, not_finite, unknown_model, no_rotation = info(), info(), info(), info()
    too_large.width, too_large.height = 1, 100000  # aborted rectify's cv::remap before the guard checked it
    not_finite.K[0] = float("nan")
    unknown_model.distortion_model = "my_own_model"
    no_rotation.R = [0.0] * 9
    return [("too_large", too_large), ("not_finite", not_finite), ("unknown_distortion_model", unknown_model),
            ("rectification_not_rotation", no_rotation),
            ("stamp_in_future", info(stamp=now + rospy.Duration(1000.0)))]


def bad_odometry(now):
    """(code the planner must give, Odometry) for each bad kind."""
    def odometry(stamp=now):
        msg = Odometry()
        msg.header.stamp = stamp
        msg.header.frame_id, msg.child_frame_id = "odom", "base_link"
        msg.pose.pose.orientation.w = 1.0
        return msg
    far, zero_quaternion = odometry(), odometry()
    far.pose.pose.position.x = 1e30
    zero_quaternion.pose.pose.orientation.w = 0.0
    return [("odometry_position_out_of_bounds", far), ("odometry_orientation_not_unit", zero_quaternion),
            ("stamp_in_future", odometry(stamp=now + rospy.Duration(1000.0)))]


def bad_estimates(source, now):
    """(code the consumer must give, TargetEstimate) for each bad kind, all at the marker range."""
    def estimate(stamp):
        msg = TargetEstimate()
        msg.header.stamp = stamp
        msg.header.frame_id = "stereo_left_optical_frame"
        msg.source = msg.selected_source = source
        msg.valid = msg.position_valid = msg.orientation_valid = True
        msg.pose.pose.position.z = MARKER_RANGE_M
        msg.pose.pose.orientation.w = 1.0
        msg.range_m = MARKER_RANGE_M
        msg.feature_inliers = 100
        msg.reprojection_error_px = 0.5
        for i in range(6):
            msg.pose.covariance[i * 7] = 1e-4
        return msg
    future = estimate(now + rospy.Duration(1000.0))
    zero_quaternion = estimate(now)
    zero_quaternion.pose.pose.orientation.w = 0.0
    nan_position = estimate(now)
    nan_position.pose.pose.position.x = float("nan")
    return [("stamp_in_future", future), ("orientation_not_unit_quaternion", zero_quaternion),
            ("position_not_finite", nan_position)]


class BadInputs(unittest.TestCase):
    @classmethod
    def setUpClass(cls):
        rospy.init_node("bad_inputs_check")

    def setUp(self):
        self.lock = threading.Lock()
        self.fused = []       # (wall time, TargetEstimate) of target/estimate from the arbiter
        self.states = []      # (wall time, DockingState)
        self.diagnostics = {}  # status name -> {key: value}, latest
        self.me = rospy.get_name()
        self.arbiter_output = rospy.Subscriber("target/estimate", TargetEstimate, self.on_fused, queue_size=50)
        rospy.Subscriber("docking/state", DockingState, self.on_state, queue_size=50)
        rospy.Subscriber("diagnostics", DiagnosticArray, self.on_diagnostics, queue_size=50)
        self.image_pubs = {c: rospy.Publisher(c + "/image_raw", Image, queue_size=20) for c in CAMERAS}
        self.info_pubs = {c: rospy.Publisher(c + "/camera_info", CameraInfo, queue_size=20) for c in CAMERAS}
        self.odom_pub = rospy.Publisher("odom", Odometry, queue_size=20)
        self.estimate_pubs = {t: rospy.Publisher(t, TargetEstimate, queue_size=20) for t in ESTIMATE_TOPICS}

    def on_fused(self, msg):
        if msg._connection_header.get("callerid") == self.me:
            return  # our own injections on target/estimate
        with self.lock:
            self.fused.append((time.time(), msg))

    def on_state(self, msg):
        with self.lock:
            self.states.append((time.time(), msg))

    def on_diagnostics(self, msg):
        with self.lock:
            for status in msg.status:
                self.diagnostics[status.name] = {kv.key: kv.value for kv in status.values}

    def valid_since(self, wall_start):
        with self.lock:
            return [m for t, m in self.fused if t >= wall_start and m.valid]

    def wait_for(self, condition, timeout_s, what):
        deadline = time.time() + timeout_s
        while time.time() < deadline and not rospy.is_shutdown():
            if condition():
                return
            time.sleep(0.2)
        self.fail("timed out after %.0f s (wall) waiting for %s" % (timeout_s, what))

    def assert_alive(self):
        for node in ["/perception_manager", "/arbiter", "/planner"]:
            self.assertTrue(rosnode.rosnode_ping(node, max_count=1, verbose=False), node + " does not answer")

    def inject(self, rounds, first_round=0):
        """Each round publishes every malformed kind once. The consumers' queues hold 2 messages, so on a
        busy machine a burst loses its oldest: the order rotates from round to round so that every kind
        is the last of its burst in some round."""
        for round_index in range(first_round, first_round + rounds):
            now = rospy.Time.now()
            for camera in CAMERAS:
                for _, msg in rotated(malformed_images(CAMERA_FRAMES[camera], now), round_index):
                    self.image_pubs[camera].publish(msg)
                for _, msg in rotated(malformed_camera_infos(CAMERA_FRAMES[camera], now), round_index):
                    self.info_pubs[camera].publish(msg)
            for _, msg in rotated(bad_odometry(now), round_index):
                self.odom_pub.publish(msg)
            for topic, source in ESTIMATE_TOPICS.items():
                for _, msg in rotated(bad_estimates(source, now), round_index):
                    self.estimate_pubs[topic].publish(msg)
            time.sleep(0.3)

    def uncounted(self):
        """What the consumers' diagnostics do not (yet) count or name: the kinds, by code, and this node
        as the last publisher of a dropped message."""
        now = rospy.Time.now()
        with self.lock:
            statuses = dict(self.diagnostics)
        guards = {name: v for name, v in statuses.items() if "image guard" in name}
        arbiter = [v for name, v in statuses.items() if "target source" in name]
        planner = [v for name, v in statuses.items() if "docking planner" in name]
        missing = ["%d of 3 image guards reporting" % len(guards)] if len(guards) < 3 else []
        missing += ["the arbiter reporting"] if not arbiter else []
        missing += ["the planner reporting"] if not planner else []
        expected = []  # (consumer, values, key that counts or names)
        for name, values in guards.items():
            expected += [(name, values, "dropped: " + code) for code, _ in malformed_images("f", now)]
            expected += [(name, values, "camera_info dropped: " + code)
                         for code, _ in malformed_camera_infos("f", now)]
            expected += [(name, values, "last dropped"), (name, values, "last dropped camera_info")]
        for values in arbiter[:1]:
            expected += [("arbiter", values, "dropped: " + code) for code, _ in bad_estimates(0, now)]
            expected += [("arbiter", values, "last dropped")]
        for values in planner[:1]:
            expected += [("planner", values, "dropped: estimate: " + code) for code, _ in bad_estimates(0, now)]
            expected += [("planner", values, "dropped: odometry: " + code) for code, _ in bad_odometry(now)]
            expected += [("planner", values, "last dropped")]
        for consumer, values, key in expected:
            value = values.get(key, "")
            counted = self.me in value if key.startswith("last dropped") else int(value or "0") > 0
            if not counted:
                missing.append("%s: %s = %r" % (consumer, key, value))
        return missing

    def assert_no_injected_output(self, injected):
        """No output of the arbiter since the injection carries the marker or a non-unit orientation."""
        with self.lock:
            outputs = [m for t, m in self.fused if t >= injected]
        for msg in outputs:
            self.assertFalse(msg.valid and abs(msg.range_m - MARKER_RANGE_M) < 0.05,
                             "an injected estimate reached the arbiter's output: %s" % msg)
            if msg.valid and msg.orientation_valid:
                q = msg.pose.pose.orientation
                norm = math.sqrt(q.x * q.x + q.y * q.y + q.z * q.z + q.w * q.w)
                self.assertAlmostEqual(norm, 1.0, delta=0.01, msg="a non-unit orientation was published")

    def test_bad_inputs_end_nothing(self):
        timeout = rospy.get_param("~startup_timeout_s", 240.0)
        start = time.time()
        self.wait_for(lambda: len(self.valid_since(start)) >= 3, timeout, "valid FUSED estimates before the injection")
        self.wait_for(lambda: all(p.get_num_connections() > 0 for p in self.image_pubs.values()) and
                      all(p.get_num_connections() > 0 for p in self.info_pubs.values()) and
                      self.odom_pub.get_num_connections() > 0 and
                      all(p.get_num_connections() > 0 for p in self.estimate_pubs.values()), 30.0,
                      "the guards, the arbiter and the planner to subscribe")
        self.assert_alive()

        injected = time.time()
        self.inject(rounds=rospy.get_param("~injection_rounds", 10))
        after = time.time()
        time.sleep(1.0)
        self.assert_alive()

        # Valid estimates keep flowing, from the real estimators, after the future-stamped ones.
        self.wait_for(lambda: len(self.valid_since(after)) >= 5, rospy.get_param("~flow_timeout_s", 60.0),
                      "valid FUSED estimates after the injection")
        self.assert_no_injected_output(injected)

        # The planner still sees the target (a future stamp used to hold every later estimate back).
        self.wait_for(lambda: any(t >= after and s.target_visible for t, s in self.states), 30.0,
                      "the planner to see the target after the injection")
        # ... where it is (1.5 m ahead): odometry 1e30 m away would have placed it at absurd ranges.
        with self.lock:
            ranges = [s.range_m for t, s in self.states if t >= injected and s.target_visible]
        self.assertTrue(ranges and all(0.5 < r < 3.0 for r in ranges),
                        "target ranges after the injection: %s" % sorted(set(round(r, 2) for r in ranges))[-5:])

        # Diagnostics: each consumer counts the drops by code and names this node as their publisher. A
        # kind a busy consumer's queue lost in every round is injected again (the count must come).
        rounds = rospy.get_param("~injection_rounds", 10)
        deadline = time.time() + rospy.get_param("~diagnostics_timeout_s", 90.0)
        while self.uncounted() and time.time() < deadline and not rospy.is_shutdown():
            self.inject(rounds=1, first_round=rounds)
            rounds += 1
            time.sleep(0.7)  # the diagnostics are published once a second
        self.assertEqual(self.uncounted(), [], "after %d injection rounds, not counted or named" % rounds)
        self.assert_no_injected_output(injected)
        self.assert_alive()


if __name__ == "__main__":
    rostest.rosrun(PKG, "bad_inputs", BadInputs)
