#!/usr/bin/env python3
"""Issue 53: a node with a configuration error reports it once (FATAL, naming the key and the problem),
stays up in the same process doing nothing, and says so in its diagnostics; roslaunch does not respawn it.
Before: omni_base respawned forever (10-11 FATALs per 15 s), and `safe_radius_m: abc` read "missing"."""
import threading
import time
import unittest
import xmlrpc.client

import rosgraph
import rospy
import rostest
from diagnostic_msgs.msg import DiagnosticArray, DiagnosticStatus
from rosgraph_msgs.msg import Log

WATCH_S = 12.0  # more than ten respawn periods (respawn_delay 1 s)
NODES = {
    "/omni_base": ("/omni_base/control_rate_hz", "out of range"),
    "/planner": ("/planner/safe_radius_m", "wrong type"),
}


def node_pid(name):
    master = rosgraph.Master("/config_error_check")
    code, _, pid = xmlrpc.client.ServerProxy(master.lookupNode(name)).getPid("/config_error_check")
    return pid if code == 1 else None


class ConfigError(unittest.TestCase):
    def test_one_fatal_no_respawn_and_the_key_in_the_diagnostics(self):
        rospy.init_node("config_error_check")
        lock = threading.Lock()
        config_status = {}
        fatals = {name: [] for name in NODES}

        # rostest runs no rosout node: this test is /rosout's subscriber, and a node logs its configuration
        # error once something listens to /rosout (docking_settings/run_node.cpp), so none is missed.
        def on_log(msg):
            if msg.level == Log.FATAL and msg.name in fatals:
                with lock:
                    fatals[msg.name].append(msg.msg)

        def on_diagnostics(msg):
            for status in msg.status:
                if status.name.endswith(": Configuration"):
                    with lock:
                        config_status["/" + status.name.split(":")[0]] = status

        rospy.Subscriber("/rosout", Log, on_log)
        rospy.Subscriber("/diagnostics", DiagnosticArray, on_diagnostics)
        deadline = time.time() + 60.0
        pids = {}
        while time.time() < deadline and len(pids) < len(NODES):
            for name in NODES:
                try:
                    pids[name] = node_pid(name)
                except Exception:
                    pass
            time.sleep(0.2)
        self.assertEqual(set(pids), set(NODES), "the nodes never registered")
        time.sleep(WATCH_S)
        for name, (key, problem) in NODES.items():
            with lock:
                messages = list(fatals[name])
                status = config_status.get(name)
            print("measured: %s: %d FATAL in %.0f s: %s" % (name, len(messages), WATCH_S, messages))
            self.assertEqual(len(messages), 1, "%s: %r" % (name, messages))
            self.assertIn(key, messages[0])
            self.assertIn(problem, messages[0])
            self.assertEqual(node_pid(name), pids[name], "%s was restarted" % name)
            self.assertIsNotNone(status, "%s: no Configuration diagnostics" % name)
            self.assertEqual(status.level, DiagnosticStatus.ERROR)
            self.assertEqual({kv.key: kv.value for kv in status.values}.get("key"), key)


if __name__ == "__main__":
    rostest.rosrun("docking_planner", "config_error", ConfigError)
