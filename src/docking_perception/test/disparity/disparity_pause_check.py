#!/usr/bin/env python3
"""Issue 15: the disparity stage rests near the target and wakes when it must.

With the target 0.7 m ahead the arbiter's fused estimate is monocular and inside the detector's
pause_inside_range_m (0.8 m): the detector's diagnostics must say paused, and its frame count must not
grow over a few seconds of sim time (no disparity image processed). Then the arbiter is killed (roslaunch
respawns it): with no fused estimate for 0.3 s (kPauseMaxFusedAgeS) the detector must resubscribe (its frame
count grows), and once the new arbiter publishes near and monocular again, it must rest again.
Reads /diagnostics only.
"""
import os
import signal
import unittest

import rospy
import rostest

from diagnostics_watch import StatusWatch, pid_of

PKG = "docking_perception"
DETECTOR_STATUS = "disparity_detector"
ARBITER_NODE = "/arbiter"
CALLER = "/disparity_pause_check"


def detector_reading(values, _msg):
    """(paused, frames) of the detector's status, or None."""
    if "paused" not in values or "frames" not in values:
        return None
    return (values["paused"] == "True", int(values["frames"]))


class DisparityPause(unittest.TestCase):
    @classmethod
    def setUpClass(cls):
        rospy.init_node("disparity_pause_check")

    def setUp(self):
        self.detector = StatusWatch(DETECTOR_STATUS, detector_reading, rospy.get_param("~timeout_s", 240.0))

    def latest(self):
        return self.detector.latest()

    def wait_for(self, what, predicate):
        reading = self.detector.wait_for(what, predicate)
        if reading is None:
            self.fail("timed out waiting until %s (last detector status: %s)" % (what, self.detector.latest()))
        return reading

    def test_rests_near_and_wakes_when_the_arbiter_stops(self):
        paused_frames = self.wait_for("the detector is paused", lambda s: s[0])[1]
        rospy.sleep(3.0)  # sim time: 45 camera frames at 15 Hz
        still = self.latest()
        self.assertTrue(still[0], "the detector resumed with the target still near: %s" % (still,))
        self.assertEqual(still[1], paused_frames, "disparity frames processed while paused")

        os.kill(pid_of(CALLER, ARBITER_NODE), signal.SIGKILL)
        woke = self.wait_for("the detector processes disparity again", lambda s: s[1] > paused_frames)
        rospy.loginfo("resumed: %d frames processed after the arbiter was killed", woke[1] - paused_frames)
        self.wait_for("the detector rests again (arbiter respawned)", lambda s: s[0] and s[1] > paused_frames)


if __name__ == "__main__":
    rostest.rosrun(PKG, "disparity_pause", DisparityPause)
