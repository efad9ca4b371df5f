#!/usr/bin/env python3
"""Two computers, one ROS master: the robot's half and the laptop's half as two roslaunch processes.

The "robot" (ROS_IP=robot_ip): the simulator standing in for the cameras and the motors, omni_base,
the camera frames (sim.launch perception:=false). The "laptop" (ROS_IP=laptop_ip): the guidance chain
(guidance.launch: perception, arbiter, planner), subscribing to the images with ~image_transport. Both
against the master rostest started. The check asserts that each half's nodes advertise their own
address (so every topic between them crosses from one address to the other), then docks through the
action as closed_loop_check.py's "dock" mode does: DOCKED within 1 cm / 1 deg of the truth.
"""
import os
import pathlib
import signal
import subprocess
import sys
import time
import unittest

import rosgraph
import rospy
import rostest

sys.path.insert(0, str(pathlib.Path(__file__).resolve().parent))
from closed_loop_check import ClosedLoopCheck  # noqa: E402  (the same docking check)

PKG = "docking_planner"
WORKSPACE = pathlib.Path(__file__).resolve().parents[4]
LAUNCH = WORKSPACE / "launch"


def start_half(name, ip, launch_file, args, log_dir):
    env = dict(os.environ, ROS_IP=ip)
    env.pop("ROS_HOSTNAME", None)  # ROS_HOSTNAME would win over ROS_IP
    log = open(log_dir / ("%s.log" % name), "w")
    return subprocess.Popen(["roslaunch", str(launch_file)] + args, env=env, stdout=log,
                            stderr=subprocess.STDOUT, start_new_session=True)


def stop_half(proc):
    if proc.poll() is None:
        os.killpg(proc.pid, signal.SIGINT)
        try:
            proc.wait(timeout=30)
        except subprocess.TimeoutExpired:
            os.killpg(proc.pid, signal.SIGKILL)
            proc.wait()


class TwoComputers(ClosedLoopCheck):
    @classmethod
    def setUpClass(cls):
        super().setUpClass()
        cls.log_dir = pathlib.Path(os.environ.get("ROS_HOME", "/tmp")) / "two_computers"
        cls.log_dir.mkdir(parents=True, exist_ok=True)
        cls.robot_ip = rospy.get_param("~robot_ip")
        cls.laptop_ip = rospy.get_param("~laptop_ip")
        rtf = str(rospy.get_param("~real_time_factor", 0.3))
        cls.robot = start_half("robot", cls.robot_ip, LAUNCH / "sim.launch",
                               ["scenario:=" + rospy.get_param("~scenario"), "perception:=false",
                                "real_time_factor:=" + rtf, "camera_rate_hz:=15.0", "output:=log"], cls.log_dir)
        # use_sim_time must be on the parameter server before the laptop's nodes start.
        deadline = time.time() + 120.0
        while not rospy.has_param("/use_sim_time") and time.time() < deadline:
            time.sleep(0.2)
        cls.laptop = start_half("laptop", cls.laptop_ip, LAUNCH / "guidance.launch",
                                ["output:=log", "image_transport:=" + rospy.get_param("~image_transport", "raw")],
                                cls.log_dir)

    @classmethod
    def tearDownClass(cls):
        stop_half(cls.laptop)
        stop_half(cls.robot)

    def node_address(self, node, timeout_s=120.0):
        """The host part of a node's XML-RPC URI, as the master knows it."""
        master = rosgraph.Master("/two_computers_check")
        deadline = time.time() + timeout_s
        while time.time() < deadline:
            try:
                uri = master.lookupNode(node)
                return uri.split("//", 1)[1].split(":", 1)[0]
            except (rosgraph.MasterError, rosgraph.masterapi.Error):
                time.sleep(0.5)
        self.fail("node %s never registered (logs in %s)" % (node, self.log_dir))

    def test_closed_loop(self):
        for node, ip in (("/docking_sim", self.robot_ip), ("/omni_base", self.robot_ip),
                         ("/planner", self.laptop_ip), ("/arbiter", self.laptop_ip),
                         ("/perception_manager", self.laptop_ip)):
            self.assertEqual(self.node_address(node), ip, "%s is not on its computer's address" % node)
        self.assertIsNone(self.robot.poll(), "the robot's roslaunch ended (see %s)" % self.log_dir)
        self.assertIsNone(self.laptop.poll(), "the laptop's roslaunch ended (see %s)" % self.log_dir)
        self.check_dock()


if __name__ == "__main__":
    rostest.rosrun(PKG, "two_computers_check", TwoComputers, sys.argv)
