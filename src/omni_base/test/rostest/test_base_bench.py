#!/usr/bin/env python3
"""omni_base on the bench: the fake motor board stands in for the hardware, its ~wheels topic is
the truth of what the wheels do."""
import math
import threading
import time
import unittest

import rospy
import rostest
from diagnostic_msgs.msg import DiagnosticArray, DiagnosticStatus
from docking_msgs.msg import WheelState
from geometry_msgs.msg import Twist
from nav_msgs.msg import Odometry
from sensor_msgs.msg import JointState
from std_msgs.msg import Bool, String
from std_srvs.srv import Trigger

WHEEL_RADIUS = 0.024
STOPPED_RAD_S = 0.02 / WHEEL_RADIUS  # a wheel slower than 2 cm/s at the rim counts as stopped
# The largest /odom step beyond the commanded speed across a board reboot (test 7; the bug was 0.68 m).
MAX_ODOM_STEP_EXCESS_M = 0.03


class BaseBench(unittest.TestCase):
    @classmethod
    def setUpClass(cls):
        rospy.init_node("test_base_bench")
        cls.lock = threading.Lock()
        cls.odom = None
        cls.wheels = []  # (stamp, max |speed|)
        cls.link_levels = []  # (stamp, level)
        cls.encoder_levels = []  # (stamp, level) of the Encoders diagnostic
        cls.odom_track = []  # (stamp, x, y) of every /odom
        cls.joint_states = []  # sensor_msgs/JointState from omni_base (for robot_state_publisher)
        cls.wheel_states = []  # docking_msgs/WheelState
        cls.cmd_pub = rospy.Publisher("/cmd_vel", Twist, queue_size=10)
        cls.estop_pub = rospy.Publisher("/e_stop", Bool, queue_size=1, latch=True)
        cls.fault_pub = rospy.Publisher("/fake_motor_board/fault", String, queue_size=1)
        rospy.Subscriber("/odom", Odometry, cls.on_odom)
        rospy.Subscriber("/fake_motor_board/wheels", JointState, cls.on_wheels)
        rospy.Subscriber("/diagnostics", DiagnosticArray, cls.on_diagnostics)
        rospy.Subscriber("/joint_states", JointState, cls.on_joint_states)
        rospy.Subscriber("/wheels/state", WheelState, cls.on_wheel_state)
        deadline = time.time() + 60.0
        while time.time() < deadline and (cls.odom is None or cls.cmd_pub.get_num_connections() == 0):
            time.sleep(0.1)
        assert cls.odom is not None, "omni_base never published /odom: the link to the fake board did not come up"

    @classmethod
    def on_odom(cls, msg):
        with cls.lock:
            cls.odom = msg
            cls.odom_track.append((msg.header.stamp.to_sec(), msg.pose.pose.position.x, msg.pose.pose.position.y))

    @classmethod
    def on_wheels(cls, msg):
        with cls.lock:
            cls.wheels.append((msg.header.stamp.to_sec(), max(abs(v) for v in msg.velocity)))

    @classmethod
    def on_joint_states(cls, msg):
        with cls.lock:
            cls.joint_states.append(msg)

    @classmethod
    def on_wheel_state(cls, msg):
        with cls.lock:
            cls.wheel_states.append(msg)

    @classmethod
    def on_diagnostics(cls, msg):
        for status in msg.status:
            if status.name.endswith("Motor link"):
                with cls.lock:
                    cls.link_levels.append((rospy.get_time(), status.level))
            elif status.name.endswith("Encoders"):
                with cls.lock:
                    cls.encoder_levels.append((rospy.get_time(), status.level))

    # helpers
    def position(self):
        with self.lock:
            p = self.odom.pose.pose.position
            return p.x, p.y

    def wheel_speed_now(self):
        with self.lock:
            return self.wheels[-1][1] if self.wheels else 0.0

    def drive(self, vx, seconds, rate=20.0):
        """Publishes cmd_vel at `rate` for `seconds`; returns the ROS time of the last message."""
        msg = Twist()
        msg.linear.x = vx
        last = None
        end = time.time() + seconds
        while time.time() < end:
            self.cmd_pub.publish(msg)
            last = rospy.get_time()
            time.sleep(1.0 / rate)
        return last

    def wait_until_stopped(self, timeout=5.0):
        end = time.time() + timeout
        while time.time() < end:
            if self.wheel_speed_now() < STOPPED_RAD_S:
                time.sleep(0.3)
                if self.wheel_speed_now() < STOPPED_RAD_S:
                    return True
            time.sleep(0.05)
        return False

    # tests (unittest runs them in name order)
    def test_1_distance_at_0_2_mps_for_2_s(self):
        self.assertTrue(self.wait_until_stopped())
        x0, y0 = self.position()
        self.drive(0.2, 2.0)
        self.drive(0.0, 1.0)  # an explicit stop, then let the motors settle
        x1, y1 = self.position()
        travelled = math.hypot(x1 - x0, y1 - y0)
        print("measured: travelled %.4f m for 0.4 m commanded (lateral %.4f m)" % (travelled, y1 - y0))
        self.assertAlmostEqual(travelled, 0.4, delta=0.04, msg="travelled %.3f m" % travelled)
        self.assertLess(abs(y1 - y0), 0.01)

    def test_2_wheels_stop_within_0_6_s_of_the_last_command(self):
        self.assertTrue(self.wait_until_stopped())
        last_cmd = self.drive(0.2, 1.5)
        time.sleep(1.5)
        with self.lock:
            after = [(t, v) for t, v in self.wheels if t >= last_cmd]
        self.assertTrue(after)
        self.assertGreater(after[0][1], 5.0, "the wheels were not turning at the last command")
        stopped_at = next((t for t, v in after if v < STOPPED_RAD_S), None)
        self.assertIsNotNone(stopped_at, "the wheels never stopped")
        print("measured: wheels stopped %.3f s after the last cmd_vel" % (stopped_at - last_cmd))
        self.assertLessEqual(stopped_at - last_cmd, 0.6, "stopped %.3f s after the last command" % (stopped_at - last_cmd))
        # ...and not before the 0.5 s timeout: a stream with a gap under 0.5 s keeps the base moving.
        self.assertGreater(stopped_at - last_cmd, 0.4)

    def test_3_nan_moves_nothing(self):
        self.assertTrue(self.wait_until_stopped())
        x0, y0 = self.position()
        msg = Twist()
        msg.linear.x = float("nan")
        msg.angular.z = 0.5
        end = time.time() + 1.5
        peak = 0.0
        while time.time() < end:
            self.cmd_pub.publish(msg)
            peak = max(peak, self.wheel_speed_now())
            time.sleep(0.05)
        x1, y1 = self.position()
        self.assertLess(math.hypot(x1 - x0, y1 - y0), 0.001)
        self.assertLess(peak, STOPPED_RAD_S)

    def test_4_e_stop_latches_until_released(self):
        self.assertTrue(self.wait_until_stopped())
        self.drive(0.2, 1.0)
        self.assertGreater(self.wheel_speed_now(), 5.0)
        self.estop_pub.publish(Bool(data=True))
        self.drive(0.2, 1.0)  # commands keep coming: ignored
        self.assertLess(self.wheel_speed_now(), STOPPED_RAD_S)
        self.estop_pub.publish(Bool(data=False))  # the input goes back to false: the latch holds
        x0, _ = self.position()
        self.drive(0.2, 1.0)
        self.assertLess(self.wheel_speed_now(), STOPPED_RAD_S)
        self.assertLess(abs(self.position()[0] - x0), 0.002)
        release = rospy.ServiceProxy("/omni_base/release_e_stop", Trigger)
        release.wait_for_service(10.0)
        self.assertTrue(release().success)
        self.drive(0.2, 1.0)
        self.assertGreater(self.wheel_speed_now(), 5.0)
        self.drive(0.0, 0.5)

    def test_5_board_disconnect_stops_the_wheels_and_the_link_recovers(self):
        self.assertTrue(self.wait_until_stopped())
        self.drive(0.2, 1.0)
        self.assertGreater(self.wheel_speed_now(), 5.0)
        t_disconnect = rospy.get_time()
        self.fault_pub.publish(String(data="disconnect 2.0"))
        self.drive(0.2, 1.5)  # the operator keeps commanding: the wheels must stop anyway
        self.assertLess(self.wheel_speed_now(), STOPPED_RAD_S)
        with self.lock:
            levels = [lvl for t, lvl in self.link_levels if t > t_disconnect]
        self.assertIn(DiagnosticStatus.ERROR, levels, "diagnostics did not report the lost link")
        # The board comes back after 2 s; the driver reconnects within its back-off (<= 2 s).
        x0, _ = self.position()
        self.drive(0.2, 5.0)
        self.assertGreater(self.wheel_speed_now(), 5.0, "the link did not recover")
        self.assertGreater(self.position()[0] - x0, 0.1)
        with self.lock:
            self.assertEqual(self.link_levels[-1][1], DiagnosticStatus.OK)
        self.drive(0.0, 0.5)

    def test_6_joint_states_carry_the_wheel_angles(self):
        self.assertTrue(self.wait_until_stopped())
        names = rospy.get_param("/omni_base/wheels/names")
        angles = [math.radians(a) for a in rospy.get_param("/omni_base/wheels/drive_angles_deg")]
        r = rospy.get_param("/omni_base/wheels/radius_m")
        with self.lock:
            self.joint_states.clear()
            self.wheel_states.clear()
        self.drive(0.2, 1.5)
        self.drive(0.0, 1.0)
        with self.lock:
            joints, states = list(self.joint_states), list(self.wheel_states)
        # Every joint_states message is the WheelState of the same encoder sample: same stamp, same angles.
        # The two topics arrive on their own connections, so around the clear and the snapshot one twin of a
        # pair may be in and the other not (seen under two CPU hogs): only the joint_states stamped within
        # the collected WheelStates' span are compared.
        by_stamp = {(s.header.stamp.secs, s.header.stamp.nsecs): s for s in states}
        self.assertTrue(by_stamp, "omni_base published no WheelState")
        first, last = min(by_stamp), max(by_stamp)
        joints = [js for js in joints if first <= (js.header.stamp.secs, js.header.stamp.nsecs) <= last]
        self.assertGreater(len(joints), 50, "omni_base published too few joint_states (50 Hz for 2.5 s)")
        for js in joints:
            self.assertEqual(list(js.name), names)
            key = (js.header.stamp.secs, js.header.stamp.nsecs)
            self.assertIn(key, by_stamp, "a joint_states stamp that no WheelState has")
            self.assertEqual(list(js.position), list(by_stamp[key].position))
            self.assertEqual(list(js.velocity), list(by_stamp[key].velocity))
        # The angles advance as the base moves along x: wheel i turns by cos(a_i) * x / r (the kinematics).
        moved = [joints[-1].position[i] - joints[0].position[i] for i in range(len(names))]
        largest = max(abs(m) for m in moved)
        self.assertGreater(largest, 5.0, "the wheels hardly turned: %r" % moved)
        x_travel = sum(math.cos(a) * m for a, m in zip(angles, moved)) * r / sum(
            math.cos(a) ** 2 for a in angles)
        print("measured: joint_states over the drive: %s rad, i.e. %.3f m along x" % (
            ", ".join("%.3f" % m for m in moved), x_travel))
        for i, a in enumerate(angles):
            self.assertAlmostEqual(moved[i], math.cos(a) * x_travel / r, delta=0.05 * largest,
                                   msg="wheel %s turned %.3f rad of %r" % (names[i], moved[i], moved))
        # 0.2 m/s for 1.5 s, less the acceleration ramp, plus the stop ramp.
        self.assertAlmostEqual(x_travel, 0.3, delta=0.05)

    def test_7_fast_board_reboot_re_enables_without_an_odometry_jump(self):
        """Issue 12: a reboot moved /odom 0.68 m, ENABLE was never re-sent and diagnostics stayed OK."""
        self.assertTrue(self.wait_until_stopped())
        self.drive(0.2, 1.0)
        self.assertGreater(self.wheel_speed_now(), 5.0)
        with self.lock:
            self.odom_track.clear()
        t_reboot = rospy.get_time()
        self.fault_pub.publish(String(data="reboot"))
        self.drive(0.2, 3.0)
        self.assertGreater(self.wheel_speed_now(), 5.0, "the wheels do not turn after the reboot: ENABLE not re-sent")
        with self.lock:
            track = list(self.odom_track)
            encoder_levels = [lvl for t, lvl in self.encoder_levels if t > t_reboot]
        # Each /odom step beyond what 0.2 m/s (+25 %) explains over its stamps: a jump would add the old
        # counter values (0.68 m before the fix). The stamps are host receive times: a driver that runs
        # late on a busy machine reads several replies at once and puts their travel into one step over a
        # short span of stamps. 1 cm of slack (one missed cycle) failed once at 10.7 mm with two
        # `make test`s and two CPU hogs on the two cores; 3 cm is 150 ms of late running at 0.2 m/s and
        # still 23 times below the jump. The 1 mm bound at the reboot itself is the gtest
        # BoardSession.FastRebootWhileDriving...
        excess = [math.hypot(b[1] - a[1], b[2] - a[2]) - 0.25 * (b[0] - a[0]) for a, b in zip(track, track[1:])]
        travelled = math.hypot(track[-1][1] - track[0][1], track[-1][2] - track[0][2])
        print("measured: across the reboot, largest /odom step beyond the commanded speed %.4f m, "
              "travelled %.3f m in 3 s at 0.2 m/s" % (max(excess), travelled))
        self.assertLess(max(excess), MAX_ODOM_STEP_EXCESS_M)
        self.assertAlmostEqual(travelled, 0.6, delta=0.08)
        self.assertIn(DiagnosticStatus.ERROR, encoder_levels, "diagnostics did not report the reboot")
        self.assertEqual(encoder_levels[-1], DiagnosticStatus.OK, "diagnostics did not recover after the reboot")
        self.drive(0.0, 0.5)


if __name__ == "__main__":
    rostest.rosrun("omni_base", "base_bench", BaseBench)
