#!/usr/bin/env python3
"""Randomized message campaign (issue 12): thousands of malformed messages on every input topic of the
running stack, then a docking.

The simulator runs the closed loop with no docking goal (IDLE). From a seeded random.Random(~seed), this
node publishes ~per_topic malformed messages on each input topic, interleaved with the simulator's good
ones: images (unknown encodings, zero or huge sizes, data shorter or longer than step x height, a step
smaller than a row, absurd stamps), target estimates on every estimator topic and on target/estimate (NaN, infinity, zero and non-unit quaternions,
stamps far in the future or past, flags that contradict each other), cmd_vel
(NaN, infinity), wheel encoder frames (wrong wheel count, random counts), camera_info (huge or zero
sizes, NaN, unknown distortion models, wrong coefficient counts, no rotation, future stamps), odometry
(NaN, huge, zero quaternions, future stamps), docking goals with unusable limits (NaN, negative) and goal
ids stamped in the future, and cancels stamped in the future. Every generated message is malformed in at
least one field: a well-formed but wrong message cannot be told from a true one and is not what this
campaign tests.

Asserts: no process of the chain ended or was respawned (same pids before and after), the chaser
(simulator truth) did not move by more than 1 mm, /odom never jumped by more than 1 mm between two
messages, the planner stayed IDLE; then a docking goal docks (DOCKED).
"""
import math
import random
import sys
import threading
import time
import unittest

import actionlib
import rospy
import rostest
from chain_processes import pid_of
from docking_msgs.msg import DockAction, DockActionGoal, DockGoal, DockResult, DockingState, TargetEstimate, WheelEncoders
from geometry_msgs.msg import Twist
from nav_msgs.msg import Odometry
from actionlib_msgs.msg import GoalID, GoalStatus
from sensor_msgs.msg import CameraInfo, Image

PKG = "docking_planner"
CHAIN_NODES = ("/docking_sim", "/omni_base", "/perception_manager", "/arbiter", "/planner")
CAMERAS = ("stereo/left", "stereo/right", "ir")
ESTIMATE_TOPICS = ("perception/disparity/estimate", "perception/mono_visible/estimate",
                   "perception/mono_ir/estimate", "target/estimate")
BAD_FLOATS = (float("nan"), float("inf"), -float("inf"), 1e308, -1e308)
ENCODINGS = ("foo", "", "bgr8", "mono8", "rgb8", "mono16", "bayer_rggb8", "bayer_rggb16", "32FC1", "yuv422", "8UC3",
             "rgba16")



def bad_stamp(rng, now):
    choice = rng.randrange(5)
    if choice == 0:
        return rospy.Time(0)
    if choice == 1:
        return rospy.Time.from_sec(now + rng.choice((1.0, 1000.0, 1e6)))
    if choice == 2:
        return rospy.Time.from_sec(max(now - rng.choice((5.0, 1000.0)), 0.0))
    if choice == 3:
        return rospy.Time(2 ** 31, 0)
    return rospy.Time.from_sec(now)


class Generator:
    """Seeded malformed messages; each has at least one defect."""

    def __init__(self, seed):
        self.rng = random.Random(seed)

    def image(self, now, frame_id):
        r = self.rng
        m = Image()
        m.header.stamp = bad_stamp(r, now)
        m.header.frame_id = r.choice((frame_id, "", "no_such_frame"))
        m.encoding = r.choice(ENCODINGS)
        m.width = r.choice((0, 1, 7, 64, 640, 100000, 2 ** 31))
        m.height = r.choice((0, 1, 5, 48, 480, 100000))
        bpp = {"bgr8": 3, "rgb8": 3, "8UC3": 3, "mono16": 2, "bayer_rggb16": 2, "32FC1": 4, "rgba16": 8,
               "yuv422": 2}.get(m.encoding, 1)
        row = min(m.width * bpp, 1 << 20)
        m.step = r.choice((0, max(row - 1, 0), row, row + 3, 2 ** 31 + 1))
        size = r.choice((0, 1, 100, min(m.step * m.height, 64 * 1024), min(m.step * m.height, 64 * 1024) - 1))
        m.data = r.randbytes(max(0, min(size, 64 * 1024)))
        m.is_bigendian = r.choice((0, 1, 7))
        if m.encoding in ("bgr8", "mono8") and m.step == row and len(m.data) == m.step * m.height and m.width > 0 \
                and m.height > 0 and m.header.frame_id:
            m.data = m.data[:-1]  # well-formed by chance: make it short
        return m

    def camera_info(self, now, frame_id):
        r = self.rng
        m = CameraInfo()
        m.header.stamp = rospy.Time.from_sec(now)
        m.header.frame_id = frame_id
        m.width, m.height = 640, 480
        m.distortion_model = "plumb_bob"
        m.D = [0.0] * 5
        m.K = [500.0, 0.0, 320.0, 0.0, 500.0, 240.0, 0.0, 0.0, 1.0]
        m.R = [1.0, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 1.0]
        m.P = [500.0, 0.0, 320.0, 0.0, 0.0, 500.0, 240.0, 0.0, 0.0, 0.0, 1.0, 0.0]
        defect = r.randrange(9)
        if defect == 0:
            m.width, m.height = r.choice(((1, 100000), (100000, 1), (2 ** 31, 480), (1, 1)))
        elif defect == 1:
            m.width = m.height = 0
        elif defect == 2:
            m.K[r.randrange(9)] = r.choice(BAD_FLOATS[:3])
        elif defect == 3:
            m.distortion_model = r.choice(("", "foo", "fisheye"))
        elif defect == 4:
            m.D = [0.1] * r.choice((1, 3, 6, 14, 1000))
        elif defect == 5:
            m.R = [0.0] * 9
        elif defect == 6:
            m.header.stamp = rospy.Time.from_sec(now + r.choice((1000.0, 1e6)))
        elif defect == 7:
            m.binning_x, m.roi.x_offset, m.roi.width, m.roi.height = r.choice(((1000, 0, 0, 0), (0, 600, 100, 100)))
        else:
            m.K = [0.0] * 9
            m.P = [r.choice(BAD_FLOATS)] * 12
        return m

    def odometry(self, now):
        r = self.rng
        m = Odometry()
        m.header.stamp = bad_stamp(r, now)
        m.header.frame_id = r.choice(("odom", "", "map"))
        m.child_frame_id = "base_link"
        m.pose.pose.orientation.w = 1.0
        defect = r.randrange(5)
        if defect == 0:
            m.pose.pose.position.x = r.choice(BAD_FLOATS)
        elif defect == 1:
            m.pose.pose.orientation.w = 0.0
        elif defect == 2:
            m.header.stamp = rospy.Time.from_sec(now + r.choice((1.0, 1000.0)))
        elif defect == 3:
            m.twist.twist.linear.x = r.choice(BAD_FLOATS + (1e6,))
        else:
            m.pose.pose.position.y = r.choice((1e30, -1e9, 5e3))
        return m

    def cancel(self, now):
        r = self.rng
        m = GoalID()
        # In the future: actionlib would cancel every goal stamped before it, the planner's relay says
        # "received now". Malformed by its stamp.
        m.stamp = rospy.Time.from_sec(now + r.choice((10.0, 1000.0, 1e6)))
        m.id = r.choice(("", "fuzz-%d" % r.getrandbits(32)))
        return m

    def estimate(self, now, source):
        r = self.rng
        m = TargetEstimate()
        m.header.stamp = bad_stamp(r, now)
        m.header.frame_id = r.choice(("stereo_left_optical_frame", "ir_optical_frame", "", "nowhere"))
        m.source = r.choice((source, 7, 255))
        m.selected_source = r.choice((0, 1, 2, 3, 200))
        m.valid = r.random() < 0.8
        m.position_valid = r.random() < 0.8
        m.orientation_valid = r.random() < 0.7
        m.twist_valid = r.random() < 0.5
        p = m.pose.pose.position
        p.x, p.y, p.z = (r.choice(BAD_FLOATS + (0.1, 1.0, 3.0)) for _ in range(3))
        q = m.pose.pose.orientation
        q.x, q.y, q.z, q.w = r.choice(((0.0, 0.0, 0.0, 0.0), (0.0, 0.0, 0.0, 2.0), (float("nan"), 0.0, 0.0, 1.0),
                                       (0.1, 0.1, 0.1, 0.1), (0.0, 0.0, 0.0, 1.0)))
        m.pose.covariance = [r.choice(BAD_FLOATS + (0.0, -1.0, 1e-4)) for _ in range(36)]
        m.twist.twist.linear.x = r.choice(BAD_FLOATS + (0.0,))
        m.twist.covariance = [r.choice(BAD_FLOATS + (0.0, -1.0)) for _ in range(36)]
        m.range_m = r.choice(BAD_FLOATS + (-1.0, 0.0, 2.0))
        # At least one defect that a validator must catch, whatever the draw.
        defect = r.randrange(4)
        if defect == 0:
            p.x = float("nan")
        elif defect == 1:
            q.x, q.y, q.z, q.w = 0.0, 0.0, 0.0, 0.0
            m.orientation_valid = True
        elif defect == 2:
            m.header.stamp = rospy.Time.from_sec(now + 1000.0)
        else:
            m.pose.covariance = [float("nan")] * 36
        return m

    def cmd_vel(self):
        r = self.rng
        m = Twist()
        m.linear.x, m.linear.y, m.angular.z = (r.choice(BAD_FLOATS[:3] + (0.0, 0.1)) for _ in range(3))
        m.linear.x = r.choice(BAD_FLOATS[:3])  # non-finite: always malformed
        return m

    def encoders(self, now):
        r = self.rng
        m = WheelEncoders()
        m.header.stamp = bad_stamp(r, now)
        m.counts = [r.randrange(-2 ** 31, 2 ** 31) for _ in range(r.choice((0, 1, 2, 4, 8)))]
        m.motors_enabled = r.random() < 0.5
        m.fault = r.random() < 0.1
        return m

    def goal(self, now):
        r = self.rng
        m = DockActionGoal()
        m.header.stamp = bad_stamp(r, now)
        # Half the goal ids stamped in the future: actionlib's SimpleActionServer orders goals by that
        # stamp and would recall every later goal; the planner's relay takes them as received now.
        m.goal_id.stamp = rospy.Time(0) if r.random() < 0.5 else rospy.Time.from_sec(now + r.choice((10.0, 1e6)))
        m.goal_id.id = "fuzz-%d" % r.getrandbits(32)
        m.goal.time_budget_s = r.choice(BAD_FLOATS[:3] + (-1.0,))
        m.goal.search_timeout_s = r.choice((0.0, -5.0, float("nan")))
        m.goal.max_speed_mps = r.choice((0.0, -0.1, float("inf")))
        return m


class MessageFuzzCheck(unittest.TestCase):
    def setUp(self):
        rospy.init_node("message_fuzz_check")
        self.lock = threading.Lock()
        self.states, self.truth, self.odom_jumps = [], [], []
        self.last_odom = None
        rospy.Subscriber("docking/state", DockingState, self.on_state, queue_size=50)
        rospy.Subscriber("sim/truth/chaser", Odometry, self.on_truth, queue_size=50)
        rospy.Subscriber("odom", Odometry, self.on_odom, queue_size=200)

    def on_state(self, msg):
        with self.lock:
            self.states.append(msg)

    def on_truth(self, msg):
        with self.lock:
            self.truth.append((msg.pose.pose.position.x, msg.pose.pose.position.y))

    def on_odom(self, msg):
        if msg._connection_header.get("callerid") != "/omni_base":
            return  # our own malformed odometry
        p = msg.pose.pose.position
        with self.lock:
            if self.last_odom is not None:
                self.odom_jumps.append(math.hypot(p.x - self.last_odom[0], p.y - self.last_odom[1]))
            self.last_odom = (p.x, p.y)

    def publishers(self):
        pubs = {}
        for cam in CAMERAS:
            pubs[cam + "/image_raw"] = rospy.Publisher(cam + "/image_raw", Image, queue_size=100)
            pubs[cam + "/camera_info"] = rospy.Publisher(cam + "/camera_info", CameraInfo, queue_size=100)
        for topic in ESTIMATE_TOPICS:
            pubs[topic] = rospy.Publisher(topic, TargetEstimate, queue_size=100)
        pubs["cmd_vel"] = rospy.Publisher("cmd_vel", Twist, queue_size=100)
        pubs["wheels/encoders"] = rospy.Publisher("wheels/encoders", WheelEncoders, queue_size=100)
        pubs["docking/dock/goal"] = rospy.Publisher("docking/dock/goal", DockActionGoal, queue_size=100)
        pubs["docking/dock/cancel"] = rospy.Publisher("docking/dock/cancel", GoalID, queue_size=100)
        pubs["odom"] = rospy.Publisher("odom", Odometry, queue_size=100)
        return pubs

    def generate(self, gen, topic, now):
        if topic.endswith("/image_raw"):
            return gen.image(now, topic.split("/")[0] + "_optical_frame")
        if topic.endswith("/camera_info"):
            return gen.camera_info(now, topic.rsplit("/", 1)[0].replace("/", "_") + "_optical_frame")
        if topic == "odom":
            return gen.odometry(now)
        if topic == "docking/dock/cancel":
            return gen.cancel(now)
        if topic in ESTIMATE_TOPICS:
            return gen.estimate(now, ESTIMATE_TOPICS.index(topic) if topic != "target/estimate" else 3)
        if topic == "cmd_vel":
            return gen.cmd_vel()
        if topic == "wheels/encoders":
            return gen.encoders(now)
        return gen.goal(now)

    def where_the_docking_is(self, sim_start):
        """What a docking that never ended was doing: sim time since the goal, the planner's states since."""
        with self.lock:
            since = [m for m in self.states if m.header.stamp.to_sec() >= sim_start]
            truth = self.truth[-1] if self.truth else None
        changes = []
        for m in since:
            if not changes or changes[-1][1] != m.state_name or changes[-1][2] != m.reason:
                changes.append((m.header.stamp.to_sec() - sim_start, m.state_name, m.reason))
        return "%.1f s of sim time since the goal, %d planner states; chaser (truth) at %s; changes: %s" % (
            rospy.get_time() - sim_start, len(since), truth,
            "; ".join("%.1f s %s (%s)" % c for c in changes[-12:]))

    def test_message_fuzz_then_dock(self):
        start = time.time()
        while rospy.get_time() == 0.0:
            self.assertLess(time.time() - start, 120.0, "no /clock from the simulator")
            time.sleep(0.1)
        # The chain is up and sees the target: every process answers and the planner reports the target
        # visible (was a fixed 3 s of sim time, ~10 s wall at 0.3; the condition is observable sooner).
        wall = time.time()
        while True:
            pids = {n: pid_of(n) for n in CHAIN_NODES}
            with self.lock:
                visible = bool(self.states) and self.states[-1].target_visible and bool(self.truth)
            if None not in pids.values() and visible:
                break
            self.assertLess(time.time() - wall, 120.0, "chain not up or target not seen: pids %s, target "
                            "visible %s" % (pids, visible))
            time.sleep(0.2)
        with self.lock:
            truth0 = self.truth[-1]
        pubs = self.publishers()
        time.sleep(2.0)  # connections
        gen = Generator(rospy.get_param("~seed", 12))
        per_topic = rospy.get_param("~per_topic", 1000)
        rate_hz = rospy.get_param("~rate_hz", 400.0)
        topics = sorted(pubs)
        sent = 0
        for _ in range(per_topic):
            for topic in topics:
                pubs[topic].publish(self.generate(gen, topic, rospy.get_time()))
                sent += 1
                time.sleep(1.0 / rate_hz)
        rospy.sleep(2.0)
        after = {n: pid_of(n) for n in CHAIN_NODES}
        self.assertEqual(pids, after, "a process of the chain ended or restarted during the campaign")
        with self.lock:
            moved = math.hypot(self.truth[-1][0] - truth0[0], self.truth[-1][1] - truth0[1])
            max_jump = max(self.odom_jumps) if self.odom_jumps else 0.0
            states = {s.state_name for s in self.states}
        self.assertLess(moved, 0.001, "the chaser moved %.4f m (truth) under malformed messages" % moved)
        self.assertLess(max_jump, 0.001, "/odom jumped %.4f m under malformed messages" % max_jump)
        self.assertEqual(states, {"IDLE"}, "planner states under malformed messages: %s" % states)
        print("message_fuzz_check: %d malformed messages on %d topics (seed %d): no process ended, chaser moved "
              "%.5f m, largest /odom step %.5f m, planner IDLE" % (sent, len(topics), rospy.get_param("~seed", 12),
                                                                    moved, max_jump), flush=True)
        # Then a docking still works. The action topics' publishers stay registered: the action client
        # publishes on the same topics from this node, and unregistering then registering a topic again
        # at once races in the master's publisher updates (most likely what happened once in a loaded make
        # test: the planner got the empty update and the client's, one goal connection was dropped at once,
        # and the goal never started a docking).
        for topic, p in pubs.items():
            if topic not in ("docking/dock/goal", "docking/dock/cancel"):
                p.unregister()
        client = actionlib.SimpleActionClient("docking/dock", DockAction)
        self.assertTrue(client.wait_for_server(rospy.Duration(30.0)))
        client.send_goal(DockGoal())
        wall = time.time()
        sim_start = rospy.get_time()
        while client.get_state() == GoalStatus.PENDING:  # said apart from a docking that never ends
            self.assertLess(time.time() - wall, 60.0, "the planner never took the docking goal: %s" %
                            self.where_the_docking_is(sim_start))
            time.sleep(0.1)
        while not client.wait_for_result(rospy.Duration(1.0)):
            self.assertLess(time.time() - wall, rospy.get_param("~dock_wall_timeout_s", 600.0),
                            "no docking result: %s" % self.where_the_docking_is(sim_start))
        result = client.get_result()
        self.assertIsNotNone(result)
        self.assertEqual(result.outcome, DockResult.DOCKED, "docking after the campaign: %s" % result.reason)
        print("message_fuzz_check: then DOCKED after %.1f s (sim)" % result.duration_s, flush=True)


if __name__ == "__main__":
    rostest.rosrun(PKG, "message_fuzz_check", MessageFuzzCheck, sys.argv)
