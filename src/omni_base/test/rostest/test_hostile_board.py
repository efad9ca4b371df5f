#!/usr/bin/env python3
"""omni_base against a hostile or glitching motor board (issue 53).

The fake board's ~wheels topic carries the wheels' true angles (a reboot does not reset them): the
board's true travel is their forward kinematics. /odom must stay within 1 cm of it through one forged
reboot frame, a genuine reboot, and a reboot claim followed by the old timeline; the Motor link
diagnostics must say ERROR while the link is in doubt and OK once it is healthy again.
"""
import math
import threading
import time
import unittest

import numpy as np
import rospy
import rostest
from diagnostic_msgs.msg import DiagnosticArray, DiagnosticStatus
from geometry_msgs.msg import Twist
from nav_msgs.msg import Odometry
from sensor_msgs.msg import JointState
from std_msgs.msg import String

MAX_ODOM_ERROR_M = 0.01


class TrueTravel:
    """Integrates the base's pose from the true wheel angles (the paper's eq. 10, inverted)."""

    def __init__(self, drive_angles_deg, center_distance_m, radius_m):
        a = np.radians(drive_angles_deg)
        self.to_body = np.linalg.pinv(np.column_stack([np.cos(a), np.sin(a), np.full(len(a), center_distance_m)]))
        self.radius = radius_m
        self.last = None
        self.x = self.y = self.yaw = 0.0

    def add(self, angles):
        angles = np.array(angles)
        if self.last is not None:
            dx, dy, dyaw = self.to_body.dot(self.radius * (angles - self.last))
            mid = self.yaw + 0.5 * dyaw
            self.x += math.cos(mid) * dx - math.sin(mid) * dy
            self.y += math.sin(mid) * dx + math.cos(mid) * dy
            self.yaw += dyaw
        self.last = angles


class HostileBoard(unittest.TestCase):
    @classmethod
    def setUpClass(cls):
        rospy.init_node("test_hostile_board")
        cls.lock = threading.Lock()
        cls.odom = None
        cls.truth = TrueTravel(rospy.get_param("/omni_base/wheels/drive_angles_deg"),
                               rospy.get_param("/omni_base/wheels/center_distance_m"),
                               rospy.get_param("/omni_base/wheels/radius_m"))
        cls.link = []        # (wall time, level, message) of /omni_base's Motor link
        cls.wrong_link = []  # (wall time, level, {key: value}) of /wrong_board/omni_base's Motor link
        cls.cmd_pub = rospy.Publisher("/cmd_vel", Twist, queue_size=10)
        cls.fault_pub = rospy.Publisher("/fake_motor_board/fault", String, queue_size=1)
        rospy.Subscriber("/odom", Odometry, cls.on_odom)
        rospy.Subscriber("/fake_motor_board/wheels", JointState, cls.on_wheels)
        rospy.Subscriber("/diagnostics", DiagnosticArray, cls.on_diagnostics)
        deadline = time.time() + 60.0
        while time.time() < deadline and (cls.odom is None or cls.cmd_pub.get_num_connections() == 0 or
                                          cls.fault_pub.get_num_connections() == 0):
            time.sleep(0.1)
        assert cls.odom is not None, "omni_base never published /odom: the link to the fake board did not come up"

    @classmethod
    def on_odom(cls, msg):
        with cls.lock:
            cls.odom = msg.pose.pose.position

    @classmethod
    def on_wheels(cls, msg):
        with cls.lock:
            cls.truth.add(msg.position)

    @classmethod
    def on_diagnostics(cls, msg):
        now = time.time()
        for status in msg.status:
            with cls.lock:
                if status.name == "omni_base: Motor link":
                    cls.link.append((now, status.level, status.message))
                elif status.name == "wrong_board/omni_base: Motor link" or status.name.endswith("wrong_board/omni_base: Motor link"):
                    cls.wrong_link.append((now, status.level, {kv.key: kv.value for kv in status.values}))

    def drive(self, vx, seconds, rate=20.0):
        msg = Twist()
        msg.linear.x = vx
        end = time.time() + seconds
        while time.time() < end:
            self.cmd_pub.publish(msg)
            time.sleep(1.0 / rate)

    def snapshot(self):
        with self.lock:
            return (self.odom.x, self.odom.y), (self.truth.x, self.truth.y)

    def run_scenario(self, name, faults):
        """Stopped, then 1.5 s at 0.2 m/s, the faults 0.2 s apart, 2 s more, stopped: /odom's travel
        against the true travel; the Motor link levels from the first fault to the end."""
        self.drive(0.0, 1.0)
        odom0, truth0 = self.snapshot()
        self.drive(0.2, 1.5)
        t_fault = time.time()
        for fault in faults:
            self.fault_pub.publish(String(data=fault))
            self.drive(0.2, 0.2)
        self.drive(0.2, 2.0)
        self.drive(0.0, 1.5)
        time.sleep(1.5)  # the diagnostics (1 Hz) catch up
        odom1, truth1 = self.snapshot()
        odom_travel = (odom1[0] - odom0[0], odom1[1] - odom0[1])
        true_travel = (truth1[0] - truth0[0], truth1[1] - truth0[1])
        error = math.hypot(odom_travel[0] - true_travel[0], odom_travel[1] - true_travel[1])
        with self.lock:
            levels = [(lvl, text) for t, lvl, text in self.link if t > t_fault]
        print("measured: %s: /odom travelled (%.4f, %.4f) m, the wheels (%.4f, %.4f) m: %.1f mm apart; "
              "Motor link levels %s" % (name, odom_travel[0], odom_travel[1], true_travel[0], true_travel[1],
                                        1000 * error, [lvl for lvl, _ in levels]))
        self.assertGreater(true_travel[0], 0.5, "the base did not drive")
        self.assertLess(error, MAX_ODOM_ERROR_M)
        self.assertIn(DiagnosticStatus.ERROR, [lvl for lvl, _ in levels], "the doubt never reached the Motor link status")
        self.assertEqual(levels[-1][0], DiagnosticStatus.OK, "the Motor link did not recover: %s" % levels[-1][1])

    def test_1_one_forged_reboot_frame_moves_nothing(self):
        # The frame: up 2 s (the board answered 20 ms ago), counts under the since-boot limit.
        self.run_scenario("one forged reboot frame", ["forge 2000 18000 -9000 -9000"])

    def test_2_a_reboot_claim_followed_by_the_old_timeline(self):
        # Fits the host's silence (up 10 ms, a few counts): held, then refuted by the board's next frame.
        self.run_scenario("a reboot claim, then the old timeline", ["forge 10 5 0 0"])

    def test_3_a_burst_of_forged_reboot_frames(self):
        self.run_scenario("forged frames 0.2 s apart", ["forge 10 5 0 0", "forge 2000 18000 -9000 -9000",
                                                       "forge 15 0 0 0"])

    def test_4_a_genuine_reboot_is_counted(self):
        self.run_scenario("a genuine reboot", ["reboot"])

    def test_5_the_wrong_wheel_count_is_named(self):
        deadline = time.time() + 20.0
        while time.time() < deadline:
            with self.lock:
                last = self.wrong_link[-1] if self.wrong_link else None
            if last and last[2].get("board wheel count") == "4":
                break
            time.sleep(0.2)
        self.assertIsNotNone(last, "no Motor link status from the driver of the four-wheel board")
        print("measured: four-wheel board, three-wheel driver: %s" % (last,))
        self.assertEqual(last[1], DiagnosticStatus.ERROR)
        self.assertEqual(last[2].get("board wheel count"), "4")
        self.assertGreater(int(last[2].get("frames with the wrong wheel count", "0")), 0)


if __name__ == "__main__":
    rostest.rosrun("omni_base", "hostile_board", HostileBoard)
