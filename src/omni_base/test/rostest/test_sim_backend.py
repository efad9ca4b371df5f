#!/usr/bin/env python3
"""The simulator interface of omni_base: this node plays the simulator. It publishes /clock, follows
the wheel set-points with ideal motors and reports encoder counts, then checks that the set-points
are the inverse kinematics of cmd_vel, that /odom follows the counts, and that losing the encoder
feedback stops the wheels."""
import math
import threading
import time
import unittest

import rospy
import rostest
from docking_msgs.msg import WheelCommand, WheelEncoders
from geometry_msgs.msg import Twist
from nav_msgs.msg import Odometry
from rosgraph_msgs.msg import Clock


class StandInSimulator:
    """Ideal motors: each wheel turns at its set-point. Runs sim time at 2x real time."""

    def __init__(self, counts_per_rev, wheels):
        self.lock = threading.Lock()
        self.counts_per_rev = counts_per_rev
        self.setpoints = [0.0] * wheels
        self.angles = [0.0] * wheels
        self.enabled = False
        self.feedback = True
        self.commands = []  # (sim time, enable, velocities)
        self.sim_time = 1.0
        self.clock_pub = rospy.Publisher("/clock", Clock, queue_size=10)
        self.enc_pub = rospy.Publisher("/wheels/encoders", WheelEncoders, queue_size=10)
        rospy.Subscriber("/wheels/command", WheelCommand, self.on_command)
        threading.Thread(target=self.run, daemon=True).start()

    def on_command(self, msg):
        with self.lock:
            self.setpoints = list(msg.velocity)
            self.enabled = msg.enable
            self.commands.append((self.sim_time, msg.enable, list(msg.velocity)))

    def run(self):
        dt = 0.005
        step = 0
        while not rospy.is_shutdown():
            with self.lock:
                self.sim_time += dt
                if self.enabled:
                    for i, w in enumerate(self.setpoints):
                        self.angles[i] += w * dt
                t = self.sim_time
                angles = list(self.angles)
                feedback = self.feedback
            self.clock_pub.publish(Clock(clock=rospy.Time.from_sec(t)))
            step += 1
            if feedback and step % 2 == 0:  # encoders at 100 Hz sim time
                msg = WheelEncoders()
                msg.header.stamp = rospy.Time.from_sec(t)
                msg.counts = [int(math.floor(a / (2 * math.pi) * self.counts_per_rev)) for a in angles]
                msg.motors_enabled = True
                self.enc_pub.publish(msg)
            time.sleep(dt / 2.0)


class SimBackend(unittest.TestCase):
    @classmethod
    def setUpClass(cls):
        rospy.init_node("test_sim_backend")
        cfg = rospy.get_param("~base_config")
        cls.angles = [math.radians(a) for a in cfg["wheels"]["drive_angles_deg"]]
        cls.L = cfg["wheels"]["center_distance_m"]
        cls.r = cfg["wheels"]["radius_m"]
        cls.sim = StandInSimulator(cfg["wheels"]["encoder_counts_per_rev"], len(cls.angles))
        cls.odom = None
        cls.odom_log = []  # (stamp seconds, vx, vy, wz)
        rospy.Subscriber("/odom", Odometry, cls.on_odom)
        cls.cmd_pub = rospy.Publisher("/cmd_vel", Twist, queue_size=10)
        deadline = time.time() + 30.0
        while time.time() < deadline and (cls.odom is None or cls.cmd_pub.get_num_connections() == 0):
            time.sleep(0.1)
        assert cls.odom is not None, "omni_base did not publish /odom from the simulated encoders"

    @classmethod
    def on_odom(cls, msg):
        cls.odom = msg
        t = msg.twist.twist
        cls.odom_log.append((msg.header.stamp.to_sec(), t.linear.x, t.linear.y, t.angular.z))

    def command(self, vx, vy, wz, sim_seconds):
        msg = Twist()
        msg.linear.x, msg.linear.y, msg.angular.z = vx, vy, wz
        end = self.sim.sim_time + sim_seconds
        while self.sim.sim_time < end:
            self.cmd_pub.publish(msg)
            time.sleep(0.02)

    def test_1_setpoints_are_the_inverse_kinematics_and_odom_follows(self):
        vx, vy, wz = 0.10, -0.05, 0.3
        self.command(vx, vy, wz, 2.0)
        with self.sim.lock:
            enable, wheels = self.sim.commands[-1][1], self.sim.commands[-1][2]
        self.assertTrue(enable)
        for a, w in zip(self.angles, wheels):
            expected = (math.cos(a) * vx + math.sin(a) * vy + self.L * wz) / self.r
            self.assertAlmostEqual(w, expected, delta=1e-6)
        # One odometry twist is quantised: one encoder count is 2 pi / 1320 rad, and over a 10 ms
        # sample that is ~0.5 rad/s of wheel speed (~0.015 m/s of body speed). The mean over the last
        # second telescopes to the count change over that second, so it must match closely.
        end = self.sim.sim_time
        window = [o for o in list(self.odom_log) if end - 1.0 <= o[0] <= end]
        self.assertGreater(len(window), 20, "too few /odom messages in the last second")
        mean = [sum(o[k] for o in window) / len(window) for k in (1, 2, 3)]
        self.assertAlmostEqual(mean[0], vx, delta=0.005)
        self.assertAlmostEqual(mean[1], vy, delta=0.005)
        self.assertAlmostEqual(mean[2], wz, delta=0.03)

    def test_2_lost_encoder_feedback_stops_the_wheels(self):
        self.command(0.1, 0.0, 0.0, 1.0)
        with self.sim.lock:
            self.sim.feedback = False
            t_lost = self.sim.sim_time
        self.command(0.1, 0.0, 0.0, 1.0)
        with self.sim.lock:
            after = [c for c in self.sim.commands if c[0] > t_lost + 0.4]
            self.sim.feedback = True
        self.assertTrue(after, "no commands after the feedback stopped")
        for _, _, wheels in after:
            self.assertEqual(max(abs(w) for w in wheels), 0.0)
        # Feedback returns: the base follows cmd_vel again.
        self.command(0.1, 0.0, 0.0, 1.5)
        with self.sim.lock:
            wheels = self.sim.commands[-1][2]
        self.assertGreater(max(abs(w) for w in wheels), 1.0)


if __name__ == "__main__":
    rostest.rosrun("omni_base", "sim_backend", SimBackend)
