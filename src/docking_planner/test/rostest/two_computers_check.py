#!/usr/bin/env python3
"""Two computers, one ROS master: the robot's half and the laptop's half on two network hosts.

The hosts are two Linux network namespaces that this test makes (ip netns, root needed), joined by a
veth pair: the "robot" (robot_ip) runs the ROS master and sim.launch perception:=false (the simulator
standing in for the cameras and the motors, omni_base, the robot model); the "laptop" (laptop_ip) runs
guidance.launch (perception, arbiter, planner) with the images over ~image_transport. Every topic
between the halves crosses the veth link, addressed by ROS_IP as on a real robot network.

(Two loopback addresses such as 127.0.0.1 / 127.0.0.2 do not work for this: roscpp binds its TCPROS
server to 127.0.0.1 alone whenever ROS_IP starts with "127.", so a node advertising 127.0.0.2 refuses
every topic connection. Namespaces are real separate hosts, and need no change to the machine.)

Then, inside the laptop's namespace, this file runs again with --inside: a ClosedLoopCheck that asserts
each node advertises its own host's address and docks through the action (DOCKED within 1 cm / 1 deg of
the truth). The outer test asserts that check passed, and removes the namespaces whatever happened.
"""
import os
import pathlib
import subprocess
import sys
import time
import unittest

sys.path.insert(0, str(pathlib.Path(__file__).resolve().parent))
sys.path.insert(0, str(pathlib.Path(__file__).resolve().parents[4] / "scripts" / "tune"))
import launch_runner  # noqa: E402

PKG = "docking_planner"
WORKSPACE = pathlib.Path(__file__).resolve().parents[4]
LAUNCH = WORKSPACE / "launch"
MASTER_PORT = 11311


def run(cmd):
    return subprocess.run(cmd, stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True)


class Network:
    """Two namespaces joined by a veth pair; names carry this process's pid (no clash with a stale run)."""

    def __init__(self, robot_ip, laptop_ip, prefix_len=24):
        tag = str(os.getpid())
        self.robot, self.laptop = "dockrobot" + tag, "docklaptop" + tag
        self.robot_if, self.laptop_if = "vr" + tag, "vl" + tag  # interface names: at most 15 characters
        self.robot_ip, self.laptop_ip, self.prefix_len = robot_ip, laptop_ip, prefix_len

    def up(self):
        steps = [
            ["ip", "netns", "add", self.robot], ["ip", "netns", "add", self.laptop],
            ["ip", "link", "add", self.robot_if, "type", "veth", "peer", "name", self.laptop_if],
            ["ip", "link", "set", self.robot_if, "netns", self.robot],
            ["ip", "link", "set", self.laptop_if, "netns", self.laptop],
            ["ip", "-n", self.robot, "addr", "add", "%s/%d" % (self.robot_ip, self.prefix_len), "dev", self.robot_if],
            ["ip", "-n", self.laptop, "addr", "add", "%s/%d" % (self.laptop_ip, self.prefix_len), "dev", self.laptop_if],
            ["ip", "-n", self.robot, "link", "set", "lo", "up"], ["ip", "-n", self.laptop, "link", "set", "lo", "up"],
            ["ip", "-n", self.robot, "link", "set", self.robot_if, "up"],
            ["ip", "-n", self.laptop, "link", "set", self.laptop_if, "up"],
        ]
        for step in steps:
            done = run(step)
            if done.returncode != 0:
                raise RuntimeError("%s: %s" % (" ".join(step), done.stdout.strip()))

    def down(self):
        for ns in (self.robot, self.laptop):
            run(["ip", "netns", "del", ns])  # deleting a namespace deletes its end of the veth pair

    def env(self, ip):
        env = dict(os.environ, ROS_IP=ip, ROS_MASTER_URI="http://%s:%d" % (self.robot_ip, MASTER_PORT))
        env.pop("ROS_HOSTNAME", None)  # ROS_HOSTNAME would win over ROS_IP
        return env

    def start(self, ns, ip, cmd, log_path):
        log = open(log_path, "w")
        return subprocess.Popen(["ip", "netns", "exec", ns] + cmd, env=self.env(ip), stdout=log,
                                stderr=subprocess.STDOUT, start_new_session=True)


class TwoComputers(unittest.TestCase):
    """The outer test, started by rostest (its own master stays unused: the robot's namespace has one)."""

    def wait_for_param(self, net, name, timeout_s):
        deadline = time.time() + timeout_s
        while time.time() < deadline:
            done = subprocess.run(["ip", "netns", "exec", net.robot, "rosparam", "get", name], env=net.env(net.robot_ip),
                                  stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True)
            if done.returncode == 0:
                return
            time.sleep(1.0)
        self.fail("%s never appeared on the robot's master (see the robot's log)" % name)

    def test_two_computers_dock(self):
        import rospy
        rospy.init_node("two_computers_check")
        robot_ip, laptop_ip = rospy.get_param("~robot_ip"), rospy.get_param("~laptop_ip")
        log_dir = pathlib.Path(os.environ.get("ROS_HOME", "/tmp")) / "two_computers"
        log_dir.mkdir(parents=True, exist_ok=True)
        net = Network(robot_ip, laptop_ip)
        procs = []
        try:
            net.up()
            procs.append(net.start(net.robot, robot_ip, ["roscore", "-p", str(MASTER_PORT)], log_dir / "master.log"))
            procs.append(net.start(net.robot, robot_ip, [
                "roslaunch", "--wait", str(LAUNCH / "sim.launch"), "scenario:=" + rospy.get_param("~scenario"),
                "perception:=false", "real_time_factor:=%s" % rospy.get_param("~real_time_factor", 0.3),
                "camera_rate_hz:=15.0", "output:=log"], log_dir / "robot.log"))
            # use_sim_time (sim.launch) must be on the master before any laptop node starts.
            self.wait_for_param(net, "/use_sim_time", rospy.get_param("~startup_wall_timeout_s", 180.0))
            procs.append(net.start(net.laptop, laptop_ip, [
                "roslaunch", "--wait", str(LAUNCH / "guidance.launch"), "output:=log",
                "image_transport:=" + rospy.get_param("~image_transport", "raw")], log_dir / "laptop.log"))
            check = [sys.executable, str(pathlib.Path(__file__).resolve()), "--inside", "--text",
                     "__name:=two_computers_inside", "_robot_ip:=" + robot_ip, "_laptop_ip:=" + laptop_ip]
            check += ["_%s:=%s" % (k, rospy.get_param("~" + k)) for k in
                      ("mode", "timeout_s", "max_position_error_m", "max_yaw_error_deg")]
            inside = net.start(net.laptop, laptop_ip, check, log_dir / "check.log")
            procs.append(inside)
            code = inside.wait(timeout=rospy.get_param("~check_wall_timeout_s", 780.0))
            output = (log_dir / "check.log").read_text(errors="replace")
            print(output, flush=True)  # into the test's XML result, for CI logs
            self.assertEqual(code, 0, "the docking check on the laptop failed (logs in %s):\n%s" % (
                log_dir, output[-3000:]))
        finally:
            for proc in reversed(procs):
                launch_runner.stop(proc, timeout_s=30.0)
            net.down()


def inside_main():
    import rosgraph
    import rospy
    import rostest
    from closed_loop_check import ClosedLoopCheck

    class TwoComputersInside(ClosedLoopCheck):
        def node_address(self, node, timeout_s=180.0):
            """The host part of a node's XML-RPC URI, as the master knows it."""
            master = rosgraph.Master("/two_computers_inside")
            deadline = time.time() + timeout_s
            while time.time() < deadline:
                try:
                    return master.lookupNode(node).split("//", 1)[1].split(":", 1)[0]
                except Exception:  # not registered yet
                    time.sleep(0.5)
            self.fail("node %s never registered" % node)

        def test_closed_loop(self):
            robot_ip, laptop_ip = rospy.get_param("~robot_ip"), rospy.get_param("~laptop_ip")
            for node, ip in (("/docking_sim", robot_ip), ("/omni_base", robot_ip), ("/planner", laptop_ip),
                             ("/arbiter", laptop_ip), ("/perception_manager", laptop_ip)):
                self.assertEqual(self.node_address(node), ip, "%s is not on its computer's address" % node)
            print("two_computers: robot nodes on %s, laptop nodes on %s" % (robot_ip, laptop_ip), flush=True)
            self.check_dock()

    rostest.rosrun(PKG, "two_computers_inside", TwoComputersInside, sys.argv)


if __name__ == "__main__":
    if "--inside" in sys.argv:
        inside_main()
    else:
        import rostest
        rostest.rosrun(PKG, "two_computers_check", TwoComputers, sys.argv)
