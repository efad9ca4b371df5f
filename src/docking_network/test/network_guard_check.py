#!/usr/bin/env python3
"""Issue 53: a host outside the robot cannot stop a node, move the wheels or change a parameter; the robot's
own second computer can.

Three network hosts (Linux network namespaces joined by veth pairs): the robot, its laptop on the robot
network (robot_ip, laptop_ip), and a host outside on another network of the robot (robot_lab_ip,
outsider_ip) that routes the robot network through the robot: Linux accepts a packet for any of its
addresses on any interface, so binding to ROS_IP alone does not keep it out. The robot runs a master,
omni_base on the fake motor board, and a victim node (rob_side.launch).

Two configurations, as the README sets them up:
  A. the default: ROS_IP=127.0.0.1 on the robot. Every listening socket is on 127.0.0.1; from outside,
     every attack at every robot address is refused.
  B. the robot network: ROS_IP=robot_ip, robot_firewall.py --allow laptop_ip. Every listening socket is
     on robot_ip. A harmless call from outside answers before the firewall (the path exists); after it,
     every attack fails. The laptop then sets a parameter, drives the wheels and shuts the victim down.
After the attacks: the same processes, /odom where it was, the parameter unchanged.

The attacks, at each node (omni_base, fake_motor_board, victim) and the master: the slave API's
shutdown, publisherUpdate (a cmd_vel publisher of its own), requestTopic, paramUpdate; the master's
setParam; a direct TCPROS connection to omni_base's /odom publication.
"""
import ipaddress
import json
import os
import pathlib
import socket
import subprocess
import sys
import time
import unittest
import xmlrpc.client

PKG = "docking_network"
HERE = pathlib.Path(__file__).resolve().parent
sys.path.insert(0, str(HERE.parents[2] / "scripts" / "tune"))
import launch_runner  # noqa: E402  (one stop() for every process group a test starts)
SCRIPTS = HERE.parent / "scripts"
MASTER_PORT = 11311
NODES = ("/omni_base", "/fake_motor_board", "/victim")
GUARDED_PARAM = "/omni_base/watchdog/cmd_vel_timeout_s"
CALL_TIMEOUT_S = 2.0


def run(cmd, env=None, timeout=60):
    return subprocess.run(cmd, stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True, env=env, timeout=timeout)


class Hosts:
    """robot <-> laptop on the robot network; robot <-> outsider on another network. Names carry the pid."""

    def __init__(self, robot_ip, laptop_ip, robot_lab_ip, outsider_ip):
        tag = str(os.getpid())
        self.robot, self.laptop, self.outsider = "ngrobot" + tag, "nglaptop" + tag, "ngout" + tag
        self.ips = dict(robot=robot_ip, laptop=laptop_ip, robot_lab=robot_lab_ip, outsider=outsider_ip)
        self.robot_net = str(ipaddress.ip_network(robot_ip + "/24", strict=False))
        self.links = [("gr" + tag, "gl" + tag), ("gs" + tag, "go" + tag)]  # at most 15 characters

    def up(self):
        (r_net, l_net), (r_lab, o_lab) = self.links
        ip = self.ips
        steps = [["ip", "netns", "add", n] for n in (self.robot, self.laptop, self.outsider)] + [
            ["ip", "link", "add", r_net, "type", "veth", "peer", "name", l_net],
            ["ip", "link", "add", r_lab, "type", "veth", "peer", "name", o_lab],
            ["ip", "link", "set", r_net, "netns", self.robot], ["ip", "link", "set", l_net, "netns", self.laptop],
            ["ip", "link", "set", r_lab, "netns", self.robot], ["ip", "link", "set", o_lab, "netns", self.outsider],
            ["ip", "-n", self.robot, "addr", "add", ip["robot"] + "/24", "dev", r_net],
            ["ip", "-n", self.laptop, "addr", "add", ip["laptop"] + "/24", "dev", l_net],
            ["ip", "-n", self.robot, "addr", "add", ip["robot_lab"] + "/24", "dev", r_lab],
            ["ip", "-n", self.outsider, "addr", "add", ip["outsider"] + "/24", "dev", o_lab],
        ]
        for ns, dev in ((self.robot, r_net), (self.robot, r_lab), (self.laptop, l_net), (self.outsider, o_lab)):
            steps.append(["ip", "-n", ns, "link", "set", dev, "up"])
        for ns in (self.robot, self.laptop, self.outsider):
            steps.append(["ip", "-n", ns, "link", "set", "lo", "up"])
        # The outsider routes the robot network through the robot's other address.
        steps.append(["ip", "-n", self.outsider, "route", "add", self.robot_net, "via", ip["robot_lab"]])
        for step in steps:
            done = run(step)
            if done.returncode != 0:
                raise RuntimeError("%s: %s" % (" ".join(step), done.stdout.strip()))

    def down(self):
        for ns in (self.robot, self.laptop, self.outsider):
            run(["ip", "netns", "del", ns])

    @staticmethod
    def env(ros_ip, master_ip):
        env = dict(os.environ, ROS_IP=ros_ip, ROS_MASTER_URI="http://%s:%d" % (master_ip, MASTER_PORT))
        env.pop("ROS_HOSTNAME", None)
        return env

    def exec_cmd(self, ns, cmd):
        return ["ip", "netns", "exec", ns] + cmd

    def start(self, ns, env, cmd, log_path):
        return subprocess.Popen(self.exec_cmd(ns, cmd), env=env, stdout=open(log_path, "w"), stderr=subprocess.STDOUT,
                                start_new_session=True)

    def helper(self, ns, env, *args, timeout=120):
        """Runs this file in a namespace in one of its helper modes; returns its JSON answer."""
        done = run(self.exec_cmd(ns, [sys.executable, str(pathlib.Path(__file__).resolve())] + list(args)), env, timeout)
        if done.returncode != 0:
            raise RuntimeError("helper %s in %s failed:\n%s" % (args[0], ns, done.stdout[-3000:]))
        return json.loads(done.stdout.strip().splitlines()[-1])


# ---- helper modes (run inside a namespace) ----------------------------------------------------------

class TimeoutTransport(xmlrpc.client.Transport):
    def make_connection(self, host):
        connection = super().make_connection(host)
        connection.timeout = CALL_TIMEOUT_S
        return connection


def reachability(attempt):
    """'answered' when `attempt` reached the server (an XML-RPC fault is an answer), else why not."""
    try:
        attempt()
        return "answered"
    except ConnectionRefusedError:
        return "refused"
    except (socket.timeout, TimeoutError):
        return "timed out"
    except OSError as error:
        return "unreachable (%s)" % error.strerror
    except xmlrpc.client.Fault:
        return "answered"


def call(uri, method, *args):
    """What became of an XML-RPC call: 'answered', 'refused', 'timed out', ..."""
    return reachability(lambda: getattr(xmlrpc.client.ServerProxy(uri, transport=TimeoutTransport()), method)(*args))


def connect(host, port):
    """What became of a TCP connection to host:port."""
    return reachability(lambda: socket.create_connection((host, port), timeout=CALL_TIMEOUT_S).close())


def inventory():
    """On the robot: the nodes' URIs and pids, omni_base's TCPROS port, /odom's x, the guarded parameter."""
    import rosgraph
    import rospy
    from nav_msgs.msg import Odometry
    master = rosgraph.Master("/network_guard_inventory")
    nodes, pids = {}, {}
    deadline = time.time() + 90.0
    while time.time() < deadline and len(nodes) < len(NODES):
        for name in NODES:
            try:
                nodes[name] = master.lookupNode(name)
            except Exception:
                pass
        time.sleep(0.5)
    for name, uri in nodes.items():
        code, _, pid = xmlrpc.client.ServerProxy(uri).getPid("/network_guard_inventory")
        pids[name] = pid if code == 1 else None
    code, _, protocol = xmlrpc.client.ServerProxy(nodes["/omni_base"]).requestTopic(
        "/network_guard_inventory", "/odom", [["TCPROS"]])
    rospy.init_node("network_guard_inventory", anonymous=True, disable_signals=True)
    odom = rospy.wait_for_message("/odom", Odometry, timeout=30.0)
    print(json.dumps(dict(master=os.environ["ROS_MASTER_URI"], nodes=nodes, pids=pids,
                          tcpros=protocol[1:3] if code == 1 else None, odom_x=odom.pose.pose.position.x,
                          param=master.getParam(GUARDED_PARAM))))


def with_host(uri, host):
    port = uri.rstrip("/").rsplit(":", 1)[1]
    return "http://%s:%s/" % (host, port)


def attack(targets_json, hosts_csv, own_ip):
    """From the outsider: every attack at every robot address; the outcome of each."""
    inv = json.loads(targets_json)
    outcomes = {}
    for host in hosts_csv.split(","):
        for name, uri in inv["nodes"].items():
            target = with_host(uri, host)
            outcomes["%s %s shutdown" % (host, name)] = call(target, "shutdown", "/outsider", "attack")
            outcomes["%s %s publisherUpdate" % (host, name)] = call(
                target, "publisherUpdate", "/outsider", "/cmd_vel", ["http://%s:9/" % own_ip])
            outcomes["%s %s requestTopic" % (host, name)] = call(target, "requestTopic", "/outsider", "/odom", [["TCPROS"]])
            outcomes["%s %s paramUpdate" % (host, name)] = call(target, "paramUpdate", "/outsider", GUARDED_PARAM, 5.0)
        outcomes["%s master setParam" % host] = call(with_host(inv["master"], host), "setParam", "/outsider",
                                                     GUARDED_PARAM, 5.0)
        if inv["tcpros"]:
            outcomes["%s omni_base TCPROS" % host] = connect(host, inv["tcpros"][1])
    print(json.dumps(outcomes))


def probe(uri):
    """A harmless call (getPid): does the path from here to the node exist?"""
    print(json.dumps({"getPid": call(uri, "getPid", "/probe")}))


def trusted(victim_uri):
    """From the laptop: set a parameter, drive 2 s at 0.1 m/s, shut the victim down."""
    import rospy
    from geometry_msgs.msg import Twist
    rospy.init_node("laptop_operator", disable_signals=True)
    rospy.set_param("/network_guard/probe", 42)
    pub = rospy.Publisher("/cmd_vel", Twist, queue_size=10)
    deadline = time.time() + 20.0
    while pub.get_num_connections() == 0 and time.time() < deadline:
        time.sleep(0.1)
    msg = Twist()
    msg.linear.x = 0.1
    end = time.time() + 2.0
    while time.time() < end:
        pub.publish(msg)
        time.sleep(0.05)
    pub.publish(Twist())
    shutdown = call(victim_uri, "shutdown", "/laptop_operator", "requested by the laptop")
    print(json.dumps({"cmd_vel subscribers": pub.get_num_connections(), "shutdown victim": shutdown}))


# ---- the test -------------------------------------------------------------------------------------------

class NetworkGuard(unittest.TestCase):
    def setUp(self):
        import rospy
        rospy.init_node("network_guard_check")
        get = rospy.get_param
        self.hosts = Hosts(get("~robot_ip"), get("~laptop_ip"), get("~robot_lab_ip"), get("~outsider_ip"))
        self.log_dir = pathlib.Path(os.environ.get("ROS_HOME", "/tmp")) / "network_guard"
        self.log_dir.mkdir(parents=True, exist_ok=True)
        self.procs = []
        self.hosts.up()

    def tearDown(self):
        for proc in reversed(self.procs):
            launch_runner.stop(proc, timeout_s=30.0)
        self.hosts.down()

    def start_robot(self, ros_ip, tag):
        env = self.hosts.env(ros_ip, ros_ip)
        self.procs.append(self.hosts.start(self.hosts.robot, env, ["roscore", "-p", str(MASTER_PORT)],
                                           self.log_dir / ("master_%s.log" % tag)))
        self.procs.append(self.hosts.start(self.hosts.robot, env, [
            "roslaunch", "--wait", str(HERE / "robot_side.launch")], self.log_dir / ("robot_%s.log" % tag)))
        return env, self.hosts.helper(self.hosts.robot, env, "--inventory")

    def assert_listening_only_on(self, ros_ip):
        done = run(self.hosts.exec_cmd(self.hosts.robot, ["ss", "-Hltnu"]))
        local = [line.split()[4] for line in done.stdout.splitlines() if line.strip()]
        print("measured: listening on the robot: %s" % sorted(set(a.rsplit(":", 1)[0] for a in local)))
        self.assertTrue(local, "nothing listens on the robot")
        for address in local:
            self.assertEqual(address.rsplit(":", 1)[0].strip("[]"), ros_ip, "a socket listens on %s" % address)

    def assert_attacks_fail(self, before, env, hosts_csv):
        outcomes = self.hosts.helper(self.hosts.outsider, self.hosts.env(self.hosts.ips["outsider"], "127.0.0.1"),
                                     "--attack", json.dumps(before), hosts_csv, self.hosts.ips["outsider"])
        answered = {k: v for k, v in outcomes.items() if v == "answered"}
        print("measured: %d attacks from outside: %s" % (len(outcomes), sorted(set(outcomes.values()))))
        self.assertFalse(answered, "attacks that reached the robot: %s" % answered)
        time.sleep(1.0)
        after = self.hosts.helper(self.hosts.robot, env, "--inventory")
        self.assertEqual(after["pids"], before["pids"], "a node was stopped or restarted")
        self.assertAlmostEqual(after["odom_x"], before["odom_x"], delta=0.001, msg="the wheels moved")
        self.assertEqual(after["param"], before["param"], "the parameter changed")
        return after

    def test_1_default_configuration_loopback(self):
        env, before = self.start_robot("127.0.0.1", "loopback")
        self.assert_listening_only_on("127.0.0.1")
        ips = self.hosts.ips
        self.assert_attacks_fail(before, env, "%s,%s" % (ips["robot"], ips["robot_lab"]))

    def test_2_robot_network_with_the_firewall(self):
        ips = self.hosts.ips
        env, before = self.start_robot(ips["robot"], "robot_network")
        self.assert_listening_only_on(ips["robot"])
        outsider_env = self.hosts.env(ips["outsider"], "127.0.0.1")
        # The path exists: without the firewall the outsider's harmless call answers.
        path = self.hosts.helper(self.hosts.outsider, outsider_env, "--probe", before["nodes"]["/victim"])
        self.assertEqual(path["getPid"], "answered", "the outsider cannot reach the robot even without the firewall")
        done = run(self.hosts.exec_cmd(self.hosts.robot, [sys.executable, str(SCRIPTS / "robot_firewall.py"),
                                                          "--allow", ips["laptop"]]), env)
        self.assertEqual(done.returncode, 0, done.stdout)
        self.assert_attacks_fail(before, env, "%s,%s" % (ips["robot"], ips["robot_lab"]))
        # The robot's own second computer still can.
        laptop_env = self.hosts.env(ips["laptop"], ips["robot"])
        result = self.hosts.helper(self.hosts.laptop, laptop_env, "--trusted", before["nodes"]["/victim"])
        time.sleep(1.5)
        after = self.hosts.helper(self.hosts.robot, env, "--inventory-after-trusted")
        print("measured: the laptop: %s; /odom moved %.3f m; probe parameter %s; victim %s" % (
            result, after["odom_x"] - before["odom_x"], after["probe"], after["victim"]))
        self.assertEqual(result["shutdown victim"], "answered")
        self.assertEqual(after["probe"], 42)
        self.assertGreater(after["odom_x"] - before["odom_x"], 0.05, "the laptop's cmd_vel did not move the wheels")
        self.assertEqual(after["victim"], "gone")


def inventory_after_trusted():
    import rosgraph
    import rospy
    from nav_msgs.msg import Odometry
    master = rosgraph.Master("/network_guard_inventory")
    rospy.init_node("network_guard_inventory", anonymous=True, disable_signals=True)
    odom = rospy.wait_for_message("/odom", Odometry, timeout=30.0)
    try:
        master.lookupNode("/victim")
        victim = "registered"
    except Exception:
        victim = "gone"
    print(json.dumps(dict(odom_x=odom.pose.pose.position.x, probe=master.getParam("/network_guard/probe"),
                          victim=victim)))


if __name__ == "__main__":
    modes = {"--inventory": inventory, "--attack": attack, "--probe": probe, "--trusted": trusted,
             "--inventory-after-trusted": inventory_after_trusted}
    if len(sys.argv) > 1 and sys.argv[1] in modes:
        modes[sys.argv[1]](*sys.argv[2:])
    else:
        import rostest
        rostest.rosrun(PKG, "network_guard_check", NetworkGuard, sys.argv)
