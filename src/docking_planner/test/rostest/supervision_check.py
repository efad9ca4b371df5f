#!/usr/bin/env python3
"""Supervision rostest: processes of the guidance chain die or stall mid-docking; the launch must live on.

A docking runs in the simulator (sim.launch dock:=true: the docking client sends the goal). Each time the
chaser is moving in APPROACH or ALIGN, the next fault of ~faults is injected:
  kill_planner     the planner stalls (SIGSTOP) ~stall_wall_s, then dies (kill -9): the base's cmd_vel
                   watchdog must stop the wheels
  kill_arbiter     the same for the arbiter: the planner hears nothing and holds still
  kill_perception  the same for the nodelet manager: the arbiter hears nothing (sources silent), HOLD
  stall_perception SIGSTOP of the manager for ~stall_wall_s, then SIGCONT (the nodelet bonds break)
A death alone is not enough to test the stop: in sim time, at the tests' real-time factor, a respawned
process is back within ~0.3 s, before any stop is due; the stall keeps it gone long enough (5 s wall is
1.5 s sim at 0.3) and is itself a fault to survive.
For each: the chaser (simulator truth) must be still within ~max_stop_s (sim) of the fault, the killed
process must be back (a new pid), and the docking must resume (moving in a docking state again). Then the
docking must end in one of ~allowed_outcomes (supervision.test: DOCKED; the target stands still, so
nothing but the faults stands in its way), and every node of the chain must still answer.
"""
import math
import os
import signal
import sys
import threading
import time
import unittest

import rospy
import rostest
from chain_processes import pid_of
from docking_msgs.msg import DockActionResult, DockResult, DockingState
from nav_msgs.msg import Odometry

PKG = "docking_planner"
NODE_OF_FAULT = {"kill_planner": "/planner", "kill_arbiter": "/arbiter", "kill_perception": "/perception_manager",
                 "stall_perception": "/perception_manager"}
MOVING_STATES = (DockingState.APPROACH, DockingState.ALIGN)
STILL_SPEED_MPS = 0.005      # truth: below this (linear, and the wheel circle's speed of the turn) is still
STILL_RATE_RADPS = 0.02
CHAIN_NODES = ("/docking_sim", "/omni_base", "/perception_manager", "/arbiter", "/planner", "/dock_client")



class SupervisionCheck(unittest.TestCase):
    def setUp(self):
        rospy.init_node("supervision_check")
        self.lock = threading.Lock()
        self.states = []   # (sim time, DockingState)
        self.truth = []    # (sim time, linear speed, yaw rate)
        rospy.Subscriber("docking/state", DockingState, self.on_state, queue_size=50)
        rospy.Subscriber("sim/truth/chaser", Odometry, self.on_truth, queue_size=200)
        self.results = []
        rospy.Subscriber("docking/dock/result", DockActionResult, lambda m: self.results.append(m.result), queue_size=10)

    def on_state(self, msg):
        with self.lock:
            self.states.append((rospy.get_time(), msg))

    def on_truth(self, msg):
        t = msg.twist.twist
        with self.lock:
            self.truth.append((msg.header.stamp.to_sec(), math.hypot(t.linear.x, t.linear.y), abs(t.angular.z)))

    def latest_state(self):
        with self.lock:
            return self.states[-1][1] if self.states else None

    def moving_now(self):
        with self.lock:
            if not self.truth:
                return False
            _, v, w = self.truth[-1]
        return v > 0.03 or w > 0.1

    def wait_for(self, predicate, sim_timeout_s, what):
        start = rospy.get_time()
        wall_start = time.time()
        while not rospy.is_shutdown():
            if predicate():
                return rospy.get_time()
            self.assertLess(rospy.get_time() - start, sim_timeout_s, "timed out (sim) waiting for " + what)
            self.assertLess(time.time() - wall_start, 20.0 * sim_timeout_s + 120.0, "timed out (wall) waiting for " + what)
            time.sleep(0.02)
        self.fail("shut down while waiting for " + what)

    def still_since(self, t_fault):
        """Sim time of the first truth sample after t_fault from which the chaser stays still, or None."""
        with self.lock:
            samples = [s for s in self.truth if s[0] >= t_fault]
        first_still = None
        for t, v, w in samples:
            if v < STILL_SPEED_MPS and w < STILL_RATE_RADPS:
                if first_still is None:
                    first_still = t
            else:
                first_still = None
        return first_still

    def inject(self, fault, pid, stall_wall_s):
        os.kill(pid, signal.SIGSTOP)
        time.sleep(stall_wall_s)
        os.kill(pid, signal.SIGCONT if fault == "stall_perception" else signal.SIGKILL)

    def run_fault(self, fault, max_stop_s, stall_wall_s, resume_timeout_s):
        node = NODE_OF_FAULT[fault]
        self.wait_for(lambda: (self.latest_state() is not None and self.latest_state().state in MOVING_STATES and
                               self.moving_now() and rospy.get_time() > self.earliest_fault_s),
                      resume_timeout_s, "a moving docking state before " + fault)
        pid = pid_of(node)
        self.assertIsNotNone(pid, "%s does not answer before %s" % (node, fault))
        t_fault = rospy.get_time()
        with self.lock:
            n_states = len(self.states)
        injector = threading.Thread(target=self.inject, args=(fault, pid, stall_wall_s))
        injector.start()
        # Still within max_stop_s (sim) of the fault, and still for a while after that (while it is stopped).
        self.wait_for(lambda: rospy.get_time() > t_fault + max_stop_s + 0.3, 60.0, "time to pass after " + fault)
        self.assertTrue(injector.is_alive(), "the stall (%.1f s wall) ended before the stop could be judged" % stall_wall_s)
        t_still = self.still_since(t_fault)
        self.assertIsNotNone(t_still, "%s: the chaser (truth) never stopped after the fault" % fault)
        self.assertLessEqual(t_still - t_fault, max_stop_s,
                             "%s: the chaser (truth) stopped %.2f s (sim) after the fault" % (fault, t_still - t_fault))
        injector.join()
        with self.lock:
            holds = [s for _, s in self.states[n_states:] if s.state == DockingState.HOLD]
        if fault != "kill_planner":  # a dead planner reports nothing; the others must say HOLD
            self.assertTrue(holds, "%s: the planner never reported HOLD" % fault)
        # The process is back (a new pid, or the same one resumed) and the docking resumes.
        if fault != "stall_perception":
            self.wait_for(lambda: pid_of(node) not in (None, pid), resume_timeout_s, node + " respawned")
        t_back = self.wait_for(lambda: (self.latest_state() is not None and
                                        self.latest_state().state in MOVING_STATES and self.moving_now()),
                               resume_timeout_s, "the docking to resume after " + fault)
        print("supervision_check: %s: chaser still %.2f s (sim) after the fault; HOLD reported %s; moving again "
              "%.1f s (sim) after it" % (fault, t_still - t_fault, bool(holds), t_back - t_fault), flush=True)

    def test_supervision(self):
        start = time.time()
        while rospy.get_time() == 0.0:
            self.assertLess(time.time() - start, 120.0, "no /clock from the simulator")
            time.sleep(0.1)
        faults = rospy.get_param("~faults", ["kill_planner", "kill_arbiter", "kill_perception", "stall_perception"])
        max_stop_s = rospy.get_param("~max_stop_s", 0.6)
        stall_wall_s = rospy.get_param("~stall_wall_s", 5.0)
        resume_timeout_s = rospy.get_param("~resume_timeout_s", 60.0)
        self.earliest_fault_s = rospy.get_param("~earliest_fault_s", 3.0)  # the chain warmed up
        for fault in faults:
            self.run_fault(fault, max_stop_s, stall_wall_s, resume_timeout_s)
        t_end = self.wait_for(lambda: bool(self.results), rospy.get_param("~timeout_s", 300.0),
                              "the docking to end (a result) after the faults")
        outcome = {getattr(DockResult, n): n for n in ("DOCKED", "CANCELLED", "TIME_BUDGET", "TARGET_LOST",
                                                         "CLIENT_GONE", "REJECTED", "SHUTDOWN")}.get(
            self.results[-1].outcome, str(self.results[-1].outcome))
        allowed = rospy.get_param("~allowed_outcomes", ["DOCKED"])
        self.assertIn(outcome, allowed, "the docking ended %s: %s" % (outcome, self.results[-1].reason))
        missing = [n for n in CHAIN_NODES if n != "/dock_client" and pid_of(n) is None]
        self.assertFalse(missing, "nodes gone at the end: %s" % missing)
        print("supervision_check: the docking ended %s at %.1f s (sim) after %d faults (%s); every node of the chain "
              "answers" % (outcome, t_end, len(faults), self.results[-1].reason[:120]), flush=True)


if __name__ == "__main__":
    rostest.rosrun(PKG, "supervision_check", SupervisionCheck, sys.argv)
