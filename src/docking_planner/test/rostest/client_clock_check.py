#!/usr/bin/env python3
"""client_clock.test: the operator's client (`rosrun docking_planner dock`) against the planner on a clock
this test publishes (see the .test file). Asserts:
  1. `dock abort` started before the first /clock is still waiting ~before_clock_s later (it neither gave
     up nor claimed anything), and once the clock runs it exits 0 saying the planner is IDLE;
  2. `dock start` (the clock at ~clock_start_s) sends a goal: the planner leaves IDLE;
  3. `dock abort` cancels it: exit 0 naming the goal; `dock start` ends with its `dock: ABORTED` line,
     exit 1; the planner is IDLE.
"""
import subprocess
import sys
import threading
import time
import unittest

import rospy
import rostest
from docking_msgs.msg import DockingState
from rosgraph_msgs.msg import Clock

PKG = "docking_planner"


def client(*args):
    return subprocess.Popen(["rosrun", PKG, "dock"] + list(args), stdout=subprocess.PIPE,
                            stderr=subprocess.STDOUT, text=True)


class ClientClock(unittest.TestCase):
    @classmethod
    def setUpClass(cls):
        rospy.init_node("client_clock_check")
        cls.states = []
        rospy.Subscriber("docking/state", DockingState, cls.states.append, queue_size=50)
        cls.clock = rospy.Publisher("/clock", Clock, queue_size=10)

    def run_clock(self, start_s):
        """Publishes /clock from start_s at the wall's pace (100 Hz) until the node shuts down."""
        wall0 = time.time()
        while not rospy.is_shutdown():
            self.clock.publish(Clock(clock=rospy.Time.from_sec(start_s + time.time() - wall0)))
            time.sleep(0.01)

    def wait_for(self, what, condition, timeout_s):
        deadline = time.time() + timeout_s
        while not condition():
            self.assertLess(time.time(), deadline, "no %s within %.0f s" % (what, timeout_s))
            time.sleep(0.05)

    def test_client_on_sim_time(self):
        # 1. abort before the clock: it waits.
        early = client("abort")
        time.sleep(rospy.get_param("~before_clock_s"))
        if early.poll() is not None:
            self.fail("dock abort gave up before the clock came:\n" + early.communicate()[0])
        threading.Thread(target=self.run_clock, args=(rospy.get_param("~clock_start_s"),), daemon=True).start()
        out = early.communicate(timeout=60.0)[0]
        self.assertEqual(early.returncode, 0, out)
        self.assertIn("dock: ABORTED: no docking was running; the planner is IDLE", out)
        # 2. start, the clock far from zero.
        start = client("start")
        self.wait_for("docking state other than IDLE after dock start",
                      lambda: self.states and self.states[-1].state != DockingState.IDLE, 60.0)
        # 3. abort the running docking.
        abort = client("abort")
        out = abort.communicate(timeout=60.0)[0]
        self.assertEqual(abort.returncode, 0, out)
        self.assertIn("dock: ABORTED: docking goal", out)
        started = start.communicate(timeout=30.0)[0]
        self.assertEqual(start.returncode, 1, started)
        self.assertTrue(started.strip().splitlines()[-1].startswith("dock: ABORTED after"), started)
        self.wait_for("IDLE after dock abort", lambda: self.states[-1].state == DockingState.IDLE, 10.0)
        print("client_clock_check: %s | %s" % (out.strip().splitlines()[-1], started.strip().splitlines()[-1]),
              flush=True)


if __name__ == "__main__":
    rostest.rosrun(PKG, "client_clock_check", ClientClock, sys.argv)
