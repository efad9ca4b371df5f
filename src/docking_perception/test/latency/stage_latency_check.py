#!/usr/bin/env python3
"""Issue 15: every stage of the guidance chain reports its latency in its diagnostics, measured by the
node itself from the image's stamp to the moment it publishes what it made of that image.

For each stage (the disparity detector, the visible and IR mono pose, the arbiter, the planner) it
waits until the stage's diagnostics hold at least ~min_samples samples, then asserts that the figures
are well-formed: 0 <= median <= p95 <= max, and the max below ~max_latency_ms (5 s) of ROS time (a stage
that stamped with the wrong clock, or measured from the wrong stamp, is seconds or years off). It
prints the figures (ROS time: in the simulator, sim time; wall = sim / the real-time factor).
"""
import threading
import time
import unittest

import rospy
import rostest
from diagnostic_msgs.msg import DiagnosticArray

PKG = "docking_perception"
# diagnostic status name part -> the stage's latency label (docking_msgs/latency_window.h keys)
STAGES = {
    "disparity_detector": "image->estimate",
    "mono_pose visible": "image->estimate",
    "mono_pose ir": "image->estimate",
    "target source": "image->target estimate",
    "docking planner": "image->cmd_vel",
}


class StageLatency(unittest.TestCase):
    @classmethod
    def setUpClass(cls):
        rospy.init_node("stage_latency_check")

    def setUp(self):
        self.lock = threading.Lock()
        self.values = {}  # stage name part -> {key: value} of its latest status
        rospy.Subscriber("/diagnostics", DiagnosticArray, self.on_diagnostics, queue_size=50)

    def on_diagnostics(self, msg):
        with self.lock:
            for status in msg.status:
                for part in STAGES:
                    if part in status.name:
                        self.values[part] = {kv.key: kv.value for kv in status.values}

    def figures(self, part):
        """(samples, median, p95, max) of a stage, or None while its diagnostics lack them."""
        prefix = "latency " + STAGES[part]
        with self.lock:
            values = self.values.get(part, {})
        try:
            return (int(values[prefix + " samples"]), float(values[prefix + " median ms"]),
                    float(values[prefix + " p95 ms"]), float(values[prefix + " max ms"]))
        except (KeyError, ValueError):
            return None

    def test_every_stage_reports_its_latency(self):
        min_samples = rospy.get_param("~min_samples", 10)
        max_latency_ms = rospy.get_param("~max_latency_ms", 5000.0)
        deadline = time.time() + rospy.get_param("~timeout_s", 300.0)
        missing = list(STAGES)
        while missing and time.time() < deadline and not rospy.is_shutdown():
            missing = [p for p in STAGES if not self.figures(p) or self.figures(p)[0] < min_samples]
            time.sleep(0.5)
        self.assertEqual(missing, [], "stages without %d latency samples in their diagnostics: %s (seen: %s)"
                         % (min_samples, missing, {p: self.figures(p) for p in STAGES}))
        for part in STAGES:
            samples, median, p95, worst = self.figures(part)
            print("%-20s latency %-24s median %6.1f ms, p95 %6.1f ms, max %6.1f ms over %d samples (ROS time)"
                  % (part, STAGES[part], median, p95, worst, samples))
            self.assertTrue(0.0 <= median <= p95 <= worst, "%s: median %.1f, p95 %.1f, max %.1f ms"
                            % (part, median, p95, worst))
            self.assertLess(worst, max_latency_ms, "%s: a latency of %.1f ms (ROS time)" % (part, worst))


if __name__ == "__main__":
    rostest.rosrun(PKG, "stage_latency", StageLatency)
