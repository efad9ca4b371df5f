#!/usr/bin/env python3
"""Issue 14: the perception debug images in the closed loop (markers_sim.test, after markers_sim).
Asserts, from the topics and the estimators' diagnostics alone:
  - no work without a subscriber: while the estimates are subscribed and frames are processed, but
    nobody subscribes to a debug image, its estimator has drawn none ("debug images drawn" stays 0);
  - when subscribed: each debug image is bgr8, the size of its camera (camera_info), stamped as a frame
    of that camera, and the estimator counts what it drew;
  - lazy again: after the subscribers leave, the count stops.
Prints the perception manager's CPU per frame without and with the three debug subscribers, and each
estimator's mean CPU per debug image (docs/PERFORMANCE.md, "Debug images": measured on a still scene,
  roslaunch launch/sim.launch scenario:=eval_near_1m_on planner:=false real_time_factor:=0.3
  src/docking_viz/test/debug_images_check.py _min_frames:=150).
"""
import os
import sys
import threading
import time
import unittest
import xmlrpc.client

import rosgraph
import rosnode
import rospy
import rostest
from diagnostic_msgs.msg import DiagnosticArray
from docking_msgs.msg import TargetEstimate
from sensor_msgs.msg import CameraInfo, Image

PKG = "docking_viz"
MANAGER_NODE = "/perception_manager"
# Debug image topic -> (its estimator's diagnostic status name part, frame counter key, camera_info topic)
DEBUG_IMAGES = {
    "/perception/mono_visible/debug_image": ("mono_pose visible", "images", "/stereo/left/camera_info"),
    "/perception/mono_ir/debug_image": ("mono_pose ir", "images", "/ir/camera_info"),
    "/perception/disparity/debug_image": ("disparity_detector", "frames", "/stereo/left/camera_info"),
}
ESTIMATES = ("/perception/mono_visible/estimate", "/perception/mono_ir/estimate", "/perception/disparity/estimate")
DRAWN_KEY = "debug images drawn"
DEBUG_CPU_KEY = "debug image CPU ms (mean)"
MIN_FRAMES_DEFAULT = 15  # frames each phase spans, per estimator (~min_frames: more for a steadier CPU figure)
MIN_DEBUG_IMAGES = 5  # debug images received per topic
SETTLE_FRAMES = 3     # after the publisher dropped its last debug subscriber: frames in flight then are done
WAIT_S = 400.0        # wall: generous, a busy machine runs the simulator slowly


def cpu_seconds_of(pid):
    """utime + stime of a process, s (/proc/PID/stat fields 14 and 15)."""
    with open("/proc/%d/stat" % pid) as stat:
        fields = stat.read().rsplit(")", 1)[1].split()
    return (int(fields[11]) + int(fields[12])) / os.sysconf("SC_CLK_TCK")


def pid_of(node):
    uri = rosnode.get_api_uri(rosgraph.Master("/debug_images_check"), node)
    return xmlrpc.client.ServerProxy(uri).getPid("/debug_images_check")[2]


def outbound_topics_of(node):
    """The topics on which the node has a subscriber connected (its own view: getBusInfo, direction o)."""
    uri = rosnode.get_api_uri(rosgraph.Master("/debug_images_check"), node)
    connections = xmlrpc.client.ServerProxy(uri).getBusInfo("/debug_images_check")[2]
    return {c[4] for c in connections if len(c) > 4 and c[2] == "o"}


class DebugImages(unittest.TestCase):
    def setUp(self):
        if not rospy.core.is_initialized():  # viz_sim_check.py runs it after another check
            rospy.init_node("debug_images_check")
        self.min_frames = rospy.get_param("~min_frames", MIN_FRAMES_DEFAULT)
        self.lock = threading.Lock()
        self.diagnostics = {}  # status name part -> {key: value}
        self.updated = {}  # status name part -> wall time of its last diagnostics
        self.camera_sizes = {}  # camera_info topic -> (width, height)
        self.camera_stamps = {}  # camera_info topic -> set of stamps
        self.images = {topic: [] for topic in DEBUG_IMAGES}
        rospy.Subscriber("/diagnostics", DiagnosticArray, self.on_diagnostics, queue_size=50)
        for info_topic in {entry[2] for entry in DEBUG_IMAGES.values()}:
            rospy.Subscriber(info_topic, CameraInfo, self.on_camera_info, callback_args=info_topic, queue_size=20)
        # The estimates are wanted (as the arbiter wants them): the estimators work on every frame.
        self.estimate_subscribers = [rospy.Subscriber(t, TargetEstimate, lambda m: None) for t in ESTIMATES]

    def on_diagnostics(self, msg):
        with self.lock:
            for status in msg.status:
                for part, _, _ in DEBUG_IMAGES.values():
                    if status.name.endswith(part):
                        self.diagnostics[part] = {kv.key: kv.value for kv in status.values}
                        self.updated[part] = time.time()

    def on_camera_info(self, msg, topic):
        with self.lock:
            self.camera_sizes[topic] = (msg.width, msg.height)
            self.camera_stamps.setdefault(topic, set()).add(msg.header.stamp)

    def on_image(self, msg, topic):
        with self.lock:
            self.images[topic].append(msg)

    def counter(self, part, key):
        with self.lock:
            values = self.diagnostics.get(part, {})
        return float(values[key]) if key in values else None

    def counters(self, key):
        """One diagnostic value per debug image topic's estimator; key "frames": its own frame counter."""
        return {topic: self.counter(part, frames_key if key == "frames" else key)
                for topic, (part, frames_key, _) in DEBUG_IMAGES.items()}

    def wait_for(self, condition, what):
        deadline = time.time() + WAIT_S
        while not condition():
            self.assertLess(time.time(), deadline, what())
            time.sleep(0.5)

    def wait_frames(self, start_frames, what, frames=None):
        frames = self.min_frames if frames is None else frames

        def enough():
            now = self.counters("frames")
            return all(now[t] is not None and now[t] >= start_frames[t] + frames for t in DEBUG_IMAGES)
        self.wait_for(enough, lambda: "%s: frames %s from %s" % (what, self.counters("frames"), start_frames))
        return self.counters("frames")

    def test_debug_images(self):
        self.wait_for(lambda: all(v is not None and v > 0 for v in self.counters("frames").values()),
                      lambda: "estimators processing no frames: %s" % self.counters("frames"))
        manager = pid_of(MANAGER_NODE)

        # Without debug subscribers: frames processed, no debug image drawn.
        frames_0, cpu_0 = self.counters("frames"), cpu_seconds_of(manager)
        frames_1 = self.wait_frames(frames_0, "without debug subscribers")
        cpu_1 = cpu_seconds_of(manager)
        self.assertEqual(self.counters(DRAWN_KEY), {t: 0.0 for t in DEBUG_IMAGES},
                         "debug images drawn while nobody subscribes")

        # With a subscriber on each debug image.
        subscribers = [rospy.Subscriber(t, Image, self.on_image, callback_args=t, queue_size=5) for t in DEBUG_IMAGES]
        self.wait_for(lambda: all(len(v) >= MIN_DEBUG_IMAGES for v in self.images.values()),
                      lambda: "debug images received: %s" % {t: len(v) for t, v in self.images.items()})
        frames_2, cpu_2 = self.counters("frames"), cpu_seconds_of(manager)
        frames_3 = self.wait_frames(frames_2, "with debug subscribers")
        cpu_3 = cpu_seconds_of(manager)
        self.check_images()
        self.wait_for(lambda: all(v is not None and v >= MIN_DEBUG_IMAGES for v in self.counters(DRAWN_KEY).values()),
                      lambda: "debug images counted: %s" % self.counters(DRAWN_KEY))
        self.report(frames_0, frames_1, cpu_1 - cpu_0, frames_2, frames_3, cpu_3 - cpu_2)

        # Unsubscribed: the count stops. The publisher learns of the leaving when the connection closes, a
        # moment after the master does: settled once the manager itself has no debug image connection left
        # (getBusInfo) and each estimator has processed SETTLE_FRAMES more frames (was a whole phase of
        # ~min_frames, ~20 s wall: the disparity detector's frames come at ~2.5 Hz sim); then not one image
        # more in the next phase of ~min_frames.
        connected = outbound_topics_of(MANAGER_NODE)
        self.assertTrue(set(DEBUG_IMAGES) <= connected, "the perception manager's connections (getBusInfo) "
                        "show no debug image subscriber: %s" % sorted(connected))
        for subscriber in subscribers:
            subscriber.unregister()
        self.wait_for(lambda: all(n == 0 for n in self.topic_subscriber_counts().values()),
                      lambda: "debug image subscribers left: %s" % self.topic_subscriber_counts())
        self.wait_for(lambda: not (outbound_topics_of(MANAGER_NODE) & set(DEBUG_IMAGES)),
                      lambda: "the perception manager still connected on %s" % sorted(
                          outbound_topics_of(MANAGER_NODE) & set(DEBUG_IMAGES)))
        # Counted from diagnostics sent after that (the last ones may be up to a period older).
        disconnected = time.time()
        self.wait_for(lambda: all(self.updated.get(part, 0.0) > disconnected for part, _, _ in DEBUG_IMAGES.values()),
                      lambda: "diagnostics after the disconnection: %s" % self.updated)
        frames_4 = self.wait_frames(self.counters("frames"), "after the debug subscribers left", SETTLE_FRAMES)
        drawn_4 = self.counters(DRAWN_KEY)
        self.wait_frames(frames_4, "after the debug subscribers left, settled")
        drawn_5 = self.counters(DRAWN_KEY)
        for topic in DEBUG_IMAGES:
            self.assertEqual(drawn_5[topic], drawn_4[topic],
                             "%s: %d drawn long after its subscriber left" % (topic, drawn_5[topic] - drawn_4[topic]))

    def topic_subscriber_counts(self):
        _, subscribers, _ = rosgraph.Master("/debug_images_check").getSystemState()
        by_topic = dict(subscribers)
        return {t: len(by_topic.get(t, [])) for t in DEBUG_IMAGES}

    def check_images(self):
        with self.lock:
            images = {t: list(v) for t, v in self.images.items()}
            sizes, stamps = dict(self.camera_sizes), {t: set(s) for t, s in self.camera_stamps.items()}
        for topic, (_, _, info_topic) in DEBUG_IMAGES.items():
            self.assertIn(info_topic, sizes, "no camera_info on %s" % info_topic)
            for image in images[topic]:
                self.assertEqual(image.encoding, "bgr8", topic)
                self.assert_image_size(topic, image, sizes[info_topic])
                self.assertEqual(image.step, 3 * image.width, topic)
                self.assertEqual(len(image.data), image.step * image.height, topic)
            self.assertTrue(any(image.header.stamp in stamps[info_topic] for image in images[topic]),
                            "%s: no debug image stamped as a frame of %s" % (topic, info_topic))

    def assert_image_size(self, topic, image, camera_size):
        """The camera's size; the disparity's may be the far stage's tracking window (block matching only around
        the predicted target, 640x252 at 1.5 m), on or off as the fused estimate is fresh or not, so depending
        on the machine's load."""
        if topic != "/perception/disparity/debug_image":
            self.assertEqual((image.width, image.height), camera_size, topic)
            return
        self.assertTrue(0 < image.width <= camera_size[0] and 0 < image.height <= camera_size[1],
                        "%s: %dx%d from a %dx%d camera" % ((topic, image.width, image.height) + tuple(camera_size)))

    def report(self, frames_0, frames_1, cpu_without_s, frames_2, frames_3, cpu_with_s):
        # Frames: the stereo pair's (mono visible's count); the IR camera runs at the same rate.
        key = "/perception/mono_visible/debug_image"
        per_frame_without = 1e3 * cpu_without_s / (frames_1[key] - frames_0[key])
        per_frame_with = 1e3 * cpu_with_s / (frames_3[key] - frames_2[key])
        debug_cpu = {t.split("/")[2]: self.counter(DEBUG_IMAGES[t][0], DEBUG_CPU_KEY) for t in DEBUG_IMAGES}
        print("debug_images_check: perception manager CPU per frame: %.1f ms without debug subscribers, "
              "%.1f ms with the three (%d and %d frames); mean CPU per debug image, ms: %s" % (
                  per_frame_without, per_frame_with, frames_1[key] - frames_0[key], frames_3[key] - frames_2[key],
                  ", ".join("%s %.2f" % kv for kv in sorted(debug_cpu.items()))), flush=True)


if __name__ == "__main__":
    rostest.rosrun(PKG, "debug_images", DebugImages, sys.argv)
