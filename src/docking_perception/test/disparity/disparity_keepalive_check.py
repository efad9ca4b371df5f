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
import unittest

import rospy
import rostest

from diagnostics_watch import StatusWatch, pid_of

PKG = "docking_perception"
GUARD_STATUS = "image guard /stereo/right/image_raw"
ARBITER_NODE = "/arbiter"
CALLER = "/disparity_keepalive_check"
NEAR_RATE_HZ = 2.5   # perception.launch disparity_near_rate_hz
FAR_RATE_HZ = 7.5    # perception.launch disparity_rate_hz
CAP_KEY = "rate cap in force Hz (0: every frame)"
FULL_KEY = "passed at the full rate"


def guard_reading(values, msg):
    """(stamp s, cap in force Hz, frames passed, of them at the full rate), or None."""
    if CAP_KEY not in values or FULL_KEY not in values:
        return None
    return (msg.header.stamp.to_sec(), float(values[CAP_KEY]), int(values["passed"]), int(values[FULL_KEY]))


class DisparityKeepAlive(unittest.TestCase):
    @classmethod
    def setUpClass(cls):
        rospy.init_node("disparity_keepalive_check")

    def setUp(self):
        self.guard = StatusWatch(GUARD_STATUS, guard_reading, rospy.get_param("~timeout_s", 240.0))

    def wait_for(self, what, predicate):
        reading = self.guard.wait_for(what, predicate)
        if reading is None:
            self.fail("timed out waiting until %s (last guard status: %s)" % (what, self.guard.latest()))
        return reading

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
        os.kill(pid_of(CALLER, ARBITER_NODE), signal.SIGKILL)
        lifted = self.wait_for("frames passed at the full rate (arbiter gone)", lambda s: s[3] > end[3])
        rospy.loginfo("%d frames passed at the full rate after the arbiter was killed", lifted[3] - end[3])
        again = self.wait_for("the keep-alive cap again (arbiter respawned)",
                              lambda s: s[1] == NEAR_RATE_HZ and s[3] > end[3])
        settled = self.wait_for("3 s of sim time later", lambda s: s[0] >= again[0] + 3.0)
        self.assertEqual(settled[3], again[3], "frames passed at the full rate after the arbiter came back")


if __name__ == "__main__":
    rostest.rosrun(PKG, "disparity_keepalive", DisparityKeepAlive)
