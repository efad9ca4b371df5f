#!/usr/bin/env python3
"""Issue 15: block matching at a keep-alive rate near, full rate when the arbiter needs it.

With the target 1.5 m ahead the arbiter's fused estimate is monocular and inside the right camera's
guard near_range_m (2 m): the guard's cap in force must be perception.launch's disparity_near_rate_hz
(2.5 Hz), and the frames it passes must come at about that rate (sim time, from the diagnostics' stamps).
Then the arbiter is killed (roslaunch respawns it): with no fused estimate for near_max_fused_age_s the
guard must pass frames at the full rate (disparity_rate_hz, 7.5 Hz) again, and once the new arbiter is
on the monocular pose again, return to the keep-alive rate. Reads /diagnostics only.
"""
import os
import signal
import threading
import time
import unittest
import xmlrpc.client

import rosgraph
import rosnode
import rospy
import rostest
from diagnostic_msgs.msg import DiagnosticArray

PKG = "docking_perception"
GUARD_STATUS = "image guard /stereo/right/image_raw"
ARBITER_NODE = "/arbiter"
CALLER = "/disparity_keepalive_check"
NEAR_RATE_HZ = 2.5   # perception.launch disparity_near_rate_hz
FAR_RATE_HZ = 7.5    # perception.launch disparity_rate_hz


def pid_of(node):
    uri = rosnode.get_api_uri(rosgraph.Master(CALLER), node)
    return xmlrpc.client.ServerProxy(uri).getPid(CALLER)[2]


class DisparityKeepAlive(unittest.TestCase):
    @classmethod
    def setUpClass(cls):
        rospy.init_node("disparity_keepalive_check")

    def setUp(self):
        self.lock = threading.Lock()
        self.status = None  # (stamp s, cap in force Hz, frames passed, of them at the full rate) of the guard's latest status
        self.deadline = time.monotonic() + rospy.get_param("~timeout_s", 240.0)
        rospy.Subscriber("/diagnostics", DiagnosticArray, self.on_diagnostics, queue_size=50)

    def on_diagnostics(self, msg):
        for status in msg.status:
            if GUARD_STATUS in status.name:
                values = {kv.key: kv.value for kv in status.values}
                if "rate cap in force Hz (0: every frame)" in values and "passed at the full rate" in values:
                    with self.lock:
                        self.status = (msg.header.stamp.to_sec(), float(values["rate cap in force Hz (0: every frame)"]),
                                       int(values["passed"]), int(values["passed at the full rate"]))

    def latest(self):
        with self.lock:
            return self.status

    def wait_for(self, what, predicate):
        while time.monotonic() < self.deadline and not rospy.is_shutdown():
            status = self.latest()
            if status is not None and predicate(status):
                return status
            time.sleep(0.2)
        self.fail("timed out waiting until %s (last guard status: %s)" % (what, self.latest()))

    def test_keepalive_near_full_rate_when_the_arbiter_stops(self):
        start = self.wait_for("the keep-alive cap is in force", lambda s: s[1] == NEAR_RATE_HZ)
        end = self.wait_for("6 s of sim time at the keep-alive cap", lambda s: s[0] >= start[0] + 6.0)
        self.assertEqual(end[1], NEAR_RATE_HZ, "the cap changed with the target still near: %s" % (end,))
        rate = (end[2] - start[2]) / (end[0] - start[0])
        rospy.loginfo("right camera frames passed at %.2f Hz near", rate)
        self.assertGreater(rate, 0.5 * NEAR_RATE_HZ, "block matching must stay alive near")
        self.assertLess(rate, 1.3 * NEAR_RATE_HZ, "frames passed faster than the keep-alive cap")

        self.assertEqual(end[3], start[3], "frames passed at the full rate with the target near")

        # The cap may be back at the keep-alive rate by the next status (the arbiter respawns within about
        # a second): frames passed at the full rate are the evidence that it was lifted.
        os.kill(pid_of(ARBITER_NODE), signal.SIGKILL)
        lifted = self.wait_for("frames passed at the full rate (arbiter gone)", lambda s: s[3] > end[3])
        rospy.loginfo("%d frames passed at the full rate after the arbiter was killed", lifted[3] - end[3])
        again = self.wait_for("the keep-alive cap again (arbiter respawned)",
                              lambda s: s[1] == NEAR_RATE_HZ and s[3] > end[3])
        settled = self.wait_for("3 s of sim time later", lambda s: s[0] >= again[0] + 3.0)
        self.assertEqual(settled[3], again[3], "frames passed at the full rate after the arbiter came back")


if __name__ == "__main__":
    rostest.rosrun(PKG, "disparity_keepalive", DisparityKeepAlive)
