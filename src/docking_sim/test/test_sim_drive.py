#!/usr/bin/env python3
"""rostest: driving the chaser with /cmd_vel through omni_base moves chaser_truth as /odom says."""
import math
import sys
import time
import unittest

import rospy
import rostest
from geometry_msgs.msg import Twist
from nav_msgs.msg import Odometry


def yaw_of(q):
    return math.atan2(2.0 * (q.w * q.z + q.x * q.y), 1.0 - 2.0 * (q.y * q.y + q.z * q.z))


class SimDriveTest(unittest.TestCase):
    def setUp(self):
        self.odom = []
        self.truth = []
        rospy.Subscriber("odom", Odometry, self.odom.append, queue_size=100)
        rospy.Subscriber("sim/truth/chaser", Odometry, self.truth.append, queue_size=100)
        self.cmd_pub = rospy.Publisher("cmd_vel", Twist, queue_size=10)

    def wait_wall(self, predicate, timeout_s, what):
        start = time.time()
        while not rospy.is_shutdown() and time.time() - start < timeout_s:
            if predicate():
                return
            time.sleep(0.05)
        self.fail("timed out waiting for " + what)

    def drive(self, vx, vy, wz, sim_seconds):
        """Publishes cmd_vel at 20 Hz of sim time for sim_seconds."""
        cmd = Twist()
        cmd.linear.x, cmd.linear.y, cmd.angular.z = vx, vy, wz
        end = rospy.get_rostime().to_sec() + sim_seconds
        wall_start = time.time()
        while not rospy.is_shutdown() and rospy.get_rostime().to_sec() < end:
            self.cmd_pub.publish(cmd)
            rospy.sleep(0.05)
            self.assertLess(time.time() - wall_start, 60.0, "sim time is not advancing")

    def test_truth_follows_odometry(self):
        self.wait_wall(lambda: self.odom and self.truth and self.cmd_pub.get_num_connections() > 0, 60.0,
                       "/odom, /sim/truth/chaser and a cmd_vel subscriber")
        start_truth = self.truth[-1].pose.pose
        self.drive(0.15, 0.05, 0.3, 4.0)
        self.drive(0.0, 0.0, 0.0, 1.5)  # stop and settle: both poses are then static
        odom = self.odom[-1].pose.pose
        truth = self.truth[-1].pose.pose
        # still_3m starts the chaser at the world origin with yaw 0, so odom coincides with world.
        self.assertAlmostEqual(start_truth.position.x, 0.0, places=6)
        moved = math.hypot(truth.position.x - start_truth.position.x, truth.position.y - start_truth.position.y)
        self.assertGreater(moved, 0.3, "the chaser barely moved (%.3f m)" % moved)
        self.assertGreater(abs(yaw_of(truth.orientation)), 0.6, "the chaser barely turned")
        err = math.hypot(odom.position.x - truth.position.x, odom.position.y - truth.position.y)
        yaw_err = abs(math.remainder(yaw_of(odom.orientation) - yaw_of(truth.orientation), 2 * math.pi))
        rospy.loginfo("moved %.3f m, turned %.3f rad; odom vs truth: %.4f m, %.4f rad",
                      moved, yaw_of(truth.orientation), err, yaw_err)
        self.assertLess(err, 0.02, "odometry and truth differ by %.3f m" % err)
        self.assertLess(yaw_err, 0.02, "odometry and truth differ by %.3f rad" % yaw_err)
        # Stopped means stopped: the truth twist is zero.
        t = self.truth[-1].twist.twist
        self.assertLess(math.hypot(t.linear.x, t.linear.y) + abs(t.angular.z), 1e-3)


if __name__ == "__main__":
    rospy.init_node("test_sim_drive")
    rostest.rosrun("docking_sim", "sim_drive", SimDriveTest, sys.argv)
