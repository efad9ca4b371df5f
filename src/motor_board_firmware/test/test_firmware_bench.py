#!/usr/bin/env python3
"""omni_base_node against the motor board's firmware in simavr (motor_board_sim, plant "model"): the
probe is the truth (the duties on the board's pins, the model's wheels). Simulated time throughout."""
import math
import os
import signal
import threading
import time
import unittest
import xmlrpc.client

import numpy as np
import rosgraph
import rosnode
import rospy
import rostest
import yaml
from docking_msgs.msg import WheelState
from geometry_msgs.msg import Twist
from motor_board_firmware.msg import BoardProbe
from nav_msgs.msg import Odometry
from std_msgs.msg import Empty

HERE = os.path.dirname(os.path.abspath(__file__))
BASE = yaml.safe_load(open(os.path.join(HERE, "../../../config/omni_base.yaml")))
SIM = yaml.safe_load(open(os.path.join(HERE, "../config/board_sim.yaml")))
ANGLES = [math.radians(a) for a in BASE["wheels"]["drive_angles_deg"]]
RADIUS = BASE["wheels"]["radius_m"]
L = BASE["wheels"]["center_distance_m"]
COUNTS_PER_REV = BASE["wheels"]["encoder_counts_per_rev"]
VOLTS_PER_RAD_S = BASE["motor"]["volts_per_rad_s"]
SUPPLY = BASE["motor"]["supply_volts"]
# The model's tolerance on a wheel's speed for a commanded speed: the friction's dead band (the host
# drives open loop), half a step of the board's 8-bit PWM, and 2 % for the host's ramp still settling.
FRICTION_RAD_S = SIM["friction_volts"] / VOLTS_PER_RAD_S
PWM_HALF_STEP_RAD_S = 0.5 / 256 * SUPPLY / VOLTS_PER_RAD_S
WATCHDOG_S = 0.25
# Inverse kinematics (the paper's eq. 10) and its pseudo-inverse: wheel angles -> base displacement.
IK = np.array([[math.cos(a), math.sin(a), L] for a in ANGLES]) / RADIUS
FK = np.linalg.pinv(IK)


def integrate_truth(probes):
    """The model's true base motion over a list of probes (100 Hz): each interval's wheel angle increments
    through the kinematics, integrated along its arc. Returns the displacement in the first probe's frame."""
    x = y = yaw = 0.0
    for a, b in zip(probes, probes[1:]):
        dx, dy, dyaw = FK @ (np.array(b.wheel_angle) - np.array(a.wheel_angle))
        if abs(dyaw) > 1e-9:
            s, c = math.sin(dyaw) / dyaw, (1.0 - math.cos(dyaw)) / dyaw
        else:
            s, c = 1.0, dyaw / 2.0
        bx, by = s * dx - c * dy, c * dx + s * dy
        x += math.cos(yaw) * bx - math.sin(yaw) * by
        y += math.sin(yaw) * bx + math.cos(yaw) * by
        yaw += dyaw
    return np.array([x, y])


def yaw_of(q):
    return math.atan2(2.0 * (q.w * q.z + q.x * q.y), 1.0 - 2.0 * (q.y * q.y + q.z * q.z))


def odom_move(odom0, odom1):
    """odom1's position relative to odom0, in odom0's frame."""
    dx = odom1.pose.pose.position.x - odom0.pose.pose.position.x
    dy = odom1.pose.pose.position.y - odom0.pose.pose.position.y
    yaw0 = yaw_of(odom0.pose.pose.orientation)
    return np.array([math.cos(yaw0) * dx + math.sin(yaw0) * dy, -math.sin(yaw0) * dx + math.cos(yaw0) * dy])


class FirmwareBench(unittest.TestCase):
    @classmethod
    def setUpClass(cls):
        rospy.init_node("test_firmware_bench")
        cls.lock = threading.Lock()
        cls.probe = None
        cls.probes = []
        cls.odom = None
        cls.odom_track = []
        cls.wheel_state = None
        cls.cmd_pub = rospy.Publisher("/cmd_vel", Twist, queue_size=10)
        cls.reset_pub = rospy.Publisher("/motor_board_sim/reset", Empty, queue_size=1)
        rospy.Subscriber("/motor_board_sim/probe", BoardProbe, cls.on_probe)
        rospy.Subscriber("/odom", Odometry, cls.on_odom)
        rospy.Subscriber("/wheels/state", WheelState, cls.on_wheel_state)
        deadline = time.time() + 90.0
        while time.time() < deadline and (cls.odom is None or cls.probe is None or cls.cmd_pub.get_num_connections() == 0):
            time.sleep(0.1)
        assert cls.odom is not None, "omni_base never published /odom: the link to the simulated board did not come up"

    @classmethod
    def on_probe(cls, msg):
        with cls.lock:
            cls.probe = msg
            cls.probes.append(msg)

    @classmethod
    def on_odom(cls, msg):
        with cls.lock:
            cls.odom = msg
            cls.odom_track.append((msg.header.stamp.to_sec(), msg.pose.pose.position.x, msg.pose.pose.position.y))

    @classmethod
    def on_wheel_state(cls, msg):
        with cls.lock:
            cls.wheel_state = msg

    def sleep_sim(self, seconds):
        end = rospy.get_time() + seconds
        wall_deadline = time.time() + 60.0 + 10.0 * seconds
        while rospy.get_time() < end and time.time() < wall_deadline and not rospy.is_shutdown():
            time.sleep(0.01)

    def drive(self, vx, seconds):
        end = rospy.get_time() + seconds
        wall_deadline = time.time() + 60.0 + 10.0 * seconds
        while rospy.get_time() < end and time.time() < wall_deadline:
            self.cmd_pub.publish(self.twist(vx))
            self.sleep_sim(0.05)

    @staticmethod
    def twist(vx):
        t = Twist()
        t.linear.x = vx
        return t

    def snapshot(self):
        with self.lock:
            return self.probe, self.odom

    def wait_at_rest(self):
        """Until the model's wheels stand still (the host's stop ramp, then friction)."""
        deadline = rospy.get_time() + 10.0
        while rospy.get_time() < deadline:
            probe, _ = self.snapshot()
            if all(w == 0.0 for w in probe.wheel_speed):
                break
            self.sleep_sim(0.05)
        self.sleep_sim(0.2)  # a few host cycles: /odom from the counts latched at rest

    def test_1_commanded_wheel_speeds_and_odometry_match_the_model(self):
        self.wait_at_rest()
        probe0, odom0 = self.snapshot()
        vx = 0.2
        self.drive(vx, 1.0)  # the host's ramp (0.8 m/s^2) and the motor lag settle
        speeds = []
        end = rospy.get_time() + 2.0
        while rospy.get_time() < end:
            self.cmd_pub.publish(self.twist(vx))
            self.sleep_sim(0.05)
            probe, _ = self.snapshot()
            speeds.append(list(probe.wheel_speed))
        self.cmd_pub.publish(self.twist(0.0))
        self.wait_at_rest()
        probe1, odom1 = self.snapshot()
        commanded = IK @ np.array([vx, 0.0, 0.0])
        measured = np.mean(np.array(speeds), axis=0)
        tolerance = FRICTION_RAD_S + PWM_HALF_STEP_RAD_S + 0.02 * np.abs(commanded)
        print(f"[ FIGURE   ] wheel speeds at 0.2 m/s: commanded {np.round(commanded, 3)} rad/s, model "
              f"{np.round(measured, 3)} rad/s (tolerance {np.round(tolerance, 3)})")
        for i in range(3):
            self.assertLessEqual(abs(measured[i] - commanded[i]), tolerance[i], f"wheel {i}")
        # Odometry against the model's true travel (its wheel motion through the kinematics, integrated).
        true_move = integrate_truth(self.probes_between(probe0, probe1))
        moved = odom_move(odom0, odom1)
        travel = float(np.hypot(*true_move))
        error = float(np.hypot(*(moved - true_move)))
        print(f"[ FIGURE   ] odometry {moved[0]:.5f}, {moved[1]:.5f} m against the model's {true_move[0]:.5f}, "
              f"{true_move[1]:.5f} m: error {error * 1e3:.3f} mm = {100 * error / travel:.4f} % of {travel:.3f} m")
        self.assertGreater(travel, 0.4)
        self.assertLessEqual(error, 0.001 * travel)
        # Every edge reached the host: its wheel angles are the model's to a count.
        with self.lock:
            state = self.wheel_state
        count_rad = 2 * math.pi / COUNTS_PER_REV
        for i in range(3):
            difference = state.position[i] - probe1.wheel_angle[i]
            self.assertLessEqual(abs(difference), 1.5 * count_rad, f"wheel {i}")

    def probes_between(self, first, last):
        with self.lock:
            return [p for p in self.probes if first.header.stamp <= p.header.stamp <= last.header.stamp]

    def omni_base_pid(self):
        master = rosgraph.Master("/test_firmware_bench")
        uri = rosnode.get_api_uri(master, "/omni_base")
        _, _, pid = xmlrpc.client.ServerProxy(uri).getPid("/test_firmware_bench")
        return pid

    def test_2_host_killed_mid_drive_the_board_stops_the_motors(self):
        self.drive(0.2, 1.5)
        probe, _ = self.snapshot()
        self.assertTrue(probe.bridges_enabled and any(d != 0.0 for d in probe.duty))
        os.kill(self.omni_base_pid(), signal.SIGKILL)
        killed_at = rospy.get_time()
        self.sleep_sim(0.6)
        probe, _ = self.snapshot()
        self.assertTrue(all(d == 0.0 for d in probe.duty), "the board still drives 0.6 s after the host died")
        stop_s = probe.last_drive_stop_s - probe.last_valid_command_s
        print(f"[ FIGURE   ] host killed: the board stopped the motors {stop_s:.4f} s (simulated) after the last "
              f"valid command (the host died {killed_at:.3f}, sim clock)")
        self.assertGreater(probe.last_drive_stop_s, probe.last_valid_command_s)
        self.assertLessEqual(stop_s, WATCHDOG_S + 0.001)
        # omni_base is respawned, reconnects and drives again.
        deadline = time.time() + 60.0
        moving = False
        while time.time() < deadline and not moving:
            self.cmd_pub.publish(self.twist(0.2))
            self.sleep_sim(0.1)
            probe, _ = self.snapshot()
            moving = probe.bridges_enabled and any(d != 0.0 for d in probe.duty)
        self.assertTrue(moving, "the respawned host never drove the board again")
        self.cmd_pub.publish(self.twist(0.0))
        self.wait_at_rest()

    def test_3_board_reset_mid_drive_host_reenables_without_an_odometry_jump(self):
        self.wait_at_rest()
        probe0, odom0 = self.snapshot()
        resets0 = probe0.requested_resets
        with self.lock:
            self.odom_track = []
        self.drive(0.2, 1.0)
        self.reset_pub.publish(Empty())
        deadline = rospy.get_time() + 2.0
        while rospy.get_time() < deadline and self.snapshot()[0].requested_resets == resets0:
            self.cmd_pub.publish(self.twist(0.2))
            self.sleep_sim(0.02)
        self.assertEqual(self.snapshot()[0].requested_resets, resets0 + 1, "the board was not reset")
        # The host sees the reboot, enables the board again, and the wheels turn again.
        driving_again = False
        deadline = rospy.get_time() + 2.0
        while rospy.get_time() < deadline:
            self.cmd_pub.publish(self.twist(0.2))
            self.sleep_sim(0.05)
            probe, _ = self.snapshot()
            if probe.bridges_enabled and any(d != 0.0 for d in probe.duty):
                driving_again = True
                break
        self.assertTrue(driving_again, "the host did not re-enable the reset board")
        self.drive(0.2, 0.5)
        self.cmd_pub.publish(self.twist(0.0))
        self.wait_at_rest()
        probe1, odom1 = self.snapshot()
        with self.lock:
            track = list(self.odom_track)
        # No /odom step beyond what the commanded speed allows between two messages (+ 1 cm slack).
        worst = max((math.hypot(b[1] - a[1], b[2] - a[2]) - 0.2 * max(0.0, b[0] - a[0])
                     for a, b in zip(track, track[1:])), default=0.0)
        print(f"[ FIGURE   ] board reset mid-drive: largest /odom step beyond the commanded speed {worst * 1e3:.2f} mm")
        self.assertLess(worst, 0.01)
        # Odometry still follows the model: only the motion the board had not reported before its reset,
        # and the edges of its ~1 ms start-up, are lost (one 20 ms host cycle at 0.2 m/s: 4 mm).
        true_move = integrate_truth(self.probes_between(probe0, probe1))
        error = float(np.hypot(*(odom_move(odom0, odom1) - true_move)))
        print(f"[ FIGURE   ] board reset mid-drive: odometry off the model's travel by {error * 1e3:.2f} mm "
              f"over {np.hypot(true_move[0], true_move[1]):.3f} m")
        self.assertLess(error, 0.006)
        self.assertEqual(self.snapshot()[0].unexpected_resets, 0)
        self.assertEqual(self.snapshot()[0].firmware_encoder_glitches, 0)


if __name__ == "__main__":
    rostest.rosrun("motor_board_firmware", "firmware_bench", FirmwareBench)
