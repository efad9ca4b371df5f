#!/usr/bin/env python3
"""Issue 11: a look-alike box is refused by its appearance (disparity_decoy.test).

Reads perception/disparity/estimate and target/estimate until min_frames disparity estimates have arrived
(sim time): none may be valid, at least min_appearance_fraction of them must carry REJECT_APPEARANCE (the
box was found, target-shaped, and refused by its face), and no fused estimate may be valid.
"""
import threading
import time
import unittest

import rospy
import rostest
from docking_msgs.msg import TargetEstimate

PKG = "docking_perception"


class DisparityDecoy(unittest.TestCase):
    @classmethod
    def setUpClass(cls):
        rospy.init_node("disparity_decoy_check")

    def setUp(self):
        self.lock = threading.Lock()
        self.disparity = []
        self.fused_valid = []
        rospy.Subscriber("perception/disparity/estimate", TargetEstimate, self.on_disparity, queue_size=50)
        rospy.Subscriber("target/estimate", TargetEstimate, self.on_fused, queue_size=50)

    def on_disparity(self, msg):
        with self.lock:
            self.disparity.append(msg)

    def on_fused(self, msg):
        if msg.valid:
            with self.lock:
                self.fused_valid.append(msg)

    def test_the_box_is_refused_by_its_appearance(self):
        min_frames = rospy.get_param("~min_frames", 40)
        deadline = time.time() + rospy.get_param("~timeout_s", 300.0)
        while time.time() < deadline and not rospy.is_shutdown():
            with self.lock:
                if len(self.disparity) >= min_frames:
                    break
            time.sleep(0.2)
        with self.lock:
            estimates, fused_valid = list(self.disparity), list(self.fused_valid)
        self.assertGreaterEqual(len(estimates), min_frames, "too few disparity estimates before the timeout")
        valid = [e for e in estimates if e.valid]
        self.assertEqual(len(valid), 0, "the decoy was reported as the target: %s" %
                         ["(%.2f, %.2f, %.2f)" % (e.pose.pose.position.x, e.pose.pose.position.y,
                                                  e.pose.pose.position.z) for e in valid[:5]])
        refused = [e for e in estimates if e.reject_reason == TargetEstimate.REJECT_APPEARANCE]
        fraction = len(refused) / float(len(estimates))
        rospy.loginfo("disparity_decoy: %d estimates, %d refused by appearance (%s)", len(estimates), len(refused),
                      refused[-1].status if refused else "none")
        self.assertGreaterEqual(fraction, rospy.get_param("~min_appearance_fraction", 0.8),
                                "only %d of %d refused by appearance; last status: %s" %
                                (len(refused), len(estimates), estimates[-1].status))
        self.assertEqual(len(fused_valid), 0, "the arbiter published a valid target")


if __name__ == "__main__":
    rostest.rosrun(PKG, "disparity_decoy_check", DisparityDecoy)
