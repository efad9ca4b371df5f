#!/usr/bin/env python3
"""Closed-loop rostest checks against the simulator's truth (sim time throughout).

Every docking starts through the docking action (docking/dock), as an operator starts it. With ~idle_s
> 0 the check first waits that long without a goal and asserts that nothing moved: the planner IDLE,
every cmd_vel zero, the chaser (truth) within 1 mm of where it was.

With ~client: true the dockings are started, followed and aborted by the operator's client, as an
operator types them (`rosrun docking_planner dock start|watch|abort`), after the idle wait: the clock is
then past the client's 10 s server timeout, which it once took as a deadline on ROS time (issue 54). A
first `dock start` is aborted by `dock abort` once the chaser moves: abort must exit 0 saying the goal was
cancelled, that start must end with its `dock: ABORTED` line, the planner go IDLE and cmd_vel zero. Then a
second `dock start` docks and must end with `dock: DOCKED after ...`, exit status 0; `dock watch`, running
throughout, must have printed the DOCKED state on its own line and both ends.

mode "dock": the planner must reach DOCKED within ~timeout_s (sim); at that moment the TRUE probe tip
  (base_link x = robot.yaml's docking_probe_x_m on tf world -> chaser_truth) must be within max_position_error_m of the TRUE
  port origin (tf world -> target_truth) in the floor plane, and the chaser's x axis within
  max_yaw_error_deg of the reversed port axis.
mode "lost": this node relays the arbiter's target/estimate to the planner (remapped onto
  ~relay_topic) and, lose_after_s (sim) after the planner entered APPROACH, relays every estimate as
  "nothing found" (valid false), as if the target had vanished while perception kept running (silence
  on the topic would mean perception gone, which the planner answers with a HOLD without timeout). The planner must go to HOLD, then SEARCH, within hold_to_search_max_s, and every
  cmd_vel from HOLD until SEARCH (and SEARCH's standing wait) must be zero; the chaser must not move
  (truth) while it holds.
"""
import faulthandler
import math
import re
import signal
import subprocess
import sys
import threading
import time
import unittest

import actionlib
import rospy
import rostest
import tf2_ros
from docking_msgs.msg import DockAction, DockGoal, DockResult, DockingState, TargetEstimate
from geometry_msgs.msg import Twist

PKG = "docking_planner"
MOVING = (DockingState.APPROACH, DockingState.ALIGN, DockingState.FINAL)
STATE_LINE = re.compile(r"^\s*(?:-|[0-9.]+ s)\s+([A-Z]+)\b")  # the client's state lines: elapsed, state, ...


class Client:
    """One `rosrun docking_planner dock ...` process, its output gathered line by line."""

    def __init__(self, *args):
        self.proc = subprocess.Popen(["rosrun", PKG, "dock"] + list(args), stdout=subprocess.PIPE,
                                     stderr=subprocess.STDOUT, text=True)
        self.lines = []
        self.reader = threading.Thread(target=self.read, daemon=True)
        self.reader.start()

    def read(self):
        for line in self.proc.stdout:
            self.lines.append(line.rstrip("\n"))

    def finish(self, timeout_s, interrupt=False):
        """Exit status (None: still running after timeout_s of wall time); interrupt: Ctrl-C first."""
        if interrupt:
            self.proc.send_signal(signal.SIGINT)
        try:
            code = self.proc.wait(timeout=timeout_s)
        except subprocess.TimeoutExpired:
            return None
        self.reader.join(5.0)
        return code

    def text(self):
        return "\n".join(self.lines)


def yaw_of(q):
    return math.atan2(2.0 * (q.w * q.z + q.x * q.y), 1.0 - 2.0 * (q.y * q.y + q.z * q.z))


def wrap(a):
    return math.atan2(math.sin(a), math.cos(a))


class ClosedLoopCheck(unittest.TestCase):
    @classmethod
    def setUpClass(cls):
        rospy.init_node("closed_loop_check")

    def setUp(self):
        self.lock = threading.RLock()  # timeline() is also called with the lock held (assert messages)
        self.states = []      # (receipt sim time, DockingState)
        self.cmds = []        # (receipt sim time, Twist)
        self.relaying = True
        self.last_relayed = (0.0, 0.0)
        self.buffer = tf2_ros.Buffer(cache_time=rospy.Duration(600.0))
        self.listener = tf2_ros.TransformListener(self.buffer)
        rospy.Subscriber("docking/state", DockingState, self.on_state, queue_size=50)
        rospy.Subscriber("cmd_vel", Twist, self.on_cmd, queue_size=50)
        relay_topic = rospy.get_param("~relay_topic", "")
        if relay_topic:
            self.relay_pub = rospy.Publisher(relay_topic, TargetEstimate, queue_size=10)
            rospy.Subscriber("target/estimate", TargetEstimate, self.on_estimate, queue_size=10)

    def on_state(self, msg):
        with self.lock:
            self.states.append((rospy.get_time(), msg))

    def on_cmd(self, msg):
        with self.lock:
            self.cmds.append((rospy.get_time(), msg))

    def on_estimate(self, msg):
        if self.relaying:
            self.relay_pub.publish(msg)
            self.last_relayed = (rospy.get_time(), msg.header.stamp.to_sec())
        else:  # the target is hidden, perception still runs
            hidden = TargetEstimate(header=msg.header, source=msg.source, selected_source=msg.selected_source,
                                    valid=False, status="test: target hidden",
                                    reject_reason=TargetEstimate.REJECT_NOT_FOUND)
            self.relay_pub.publish(hidden)

    def timeline(self, n0, t_ref):
        out, prev = [], None
        with self.lock:
            for t, s in self.states[n0:]:
                if s.state_name != prev:
                    out.append("%+.2f %s (%s, visible %s)" % (s.header.stamp.to_sec() - t_ref, s.state_name,
                                                              s.reason[:60], s.target_visible))
                    prev = s.state_name
        return "; ".join(out)

    def wait_clock(self):
        wall_limit = rospy.get_param("~startup_wall_timeout_s", 120.0)
        import time
        start = time.time()
        while rospy.get_time() == 0.0:
            self.assertLess(time.time() - start, wall_limit, "no /clock from the simulator")
            time.sleep(0.1)
        return rospy.get_time()

    def truth(self, stamp):
        """(chaser x, y, yaw), (port x, y, yaw) in world at the stamp."""
        out = []
        for frame in ("chaser_truth", "target_truth"):
            tr = self.buffer.lookup_transform("world", frame, stamp, rospy.Duration(2.0))
            t, q = tr.transform.translation, tr.transform.rotation
            out.append((t.x, t.y, yaw_of(q)))
        return out

    def latest_state(self):
        with self.lock:
            return self.states[-1][1] if self.states else None

    def check_idle_then_start(self, t0):
        """~idle_s without a goal: nothing moves. Then the docking goal."""
        idle_s = rospy.get_param("~idle_s", 0.0)
        if idle_s > 0.0:
            start_truth = None
            while start_truth is None:
                try:
                    start_truth = self.truth(rospy.Time.from_sec(rospy.get_time()))[0]
                except tf2_ros.TransformException:
                    rospy.sleep(0.2)
            t_start = rospy.get_time()
            rospy.sleep(idle_s)
            now = rospy.get_time()
            end_truth = self.truth(rospy.Time.from_sec(now - 0.5))[0]
            moved = math.hypot(end_truth[0] - start_truth[0], end_truth[1] - start_truth[1])
            with self.lock:
                states = [s for t, s in self.states if t >= t_start]
                cmds = [c for t, c in self.cmds if t >= t_start]
            self.assertTrue(states and all(s.state == DockingState.IDLE for s in states),
                            "not IDLE without a goal: %s" % sorted({s.state_name for s in states}))
            self.assertTrue(all(c.linear.x == 0 and c.linear.y == 0 and c.angular.z == 0 for c in cmds),
                            "non-zero cmd_vel without a goal")
            self.assertLess(moved, 0.001, "the chaser moved %.4f m (truth) without a goal" % moved)
            print("closed_loop_check: %.0f s (sim) without a goal: IDLE, %d zero cmd_vel, chaser moved %.5f m" % (
                idle_s, len(cmds), moved), flush=True)
        if rospy.get_param("~client", False):
            self.abort_a_docking()
            self.docking = Client("start")
            return rospy.get_time()
        self.client = actionlib.SimpleActionClient("docking/dock", DockAction)
        self.assertTrue(self.client.wait_for_server(rospy.Duration(60.0)), "no docking action server")
        self.client.send_goal(DockGoal())
        return rospy.get_time()

    def abort_a_docking(self):
        """The operator's client: watch, start, abort once the chaser moves; checks every end (see above)."""
        self.watch = Client("watch")
        first = Client("start")
        deadline = rospy.get_time() + 60.0
        while rospy.get_time() < deadline:
            s = self.latest_state()
            with self.lock:
                moving = self.cmds and abs(self.cmds[-1][1].linear.x) + abs(self.cmds[-1][1].linear.y) > 0.01
            if s is not None and s.state in MOVING and moving:
                break
            self.assertIsNone(first.proc.poll(), "dock start ended before the chaser moved:\n" + first.text())
            rospy.sleep(0.1)
        self.assertIn(self.latest_state().state, MOVING, "the first docking never moved: " + first.text())
        abort = Client("abort")
        self.assertEqual(abort.finish(60.0), 0, "dock abort failed:\n" + abort.text())
        self.assertIn("dock: ABORTED: docking goal", abort.text())
        t_abort = rospy.get_time()
        self.assertEqual(first.finish(30.0), 1, "dock start after the abort:\n" + first.text())
        self.assertTrue(first.lines and first.lines[-1].startswith("dock: ABORTED after"), first.text())
        rospy.sleep(1.0)
        with self.lock:
            after = [c for t, c in self.cmds if t > t_abort + 0.2]
        self.assertEqual(self.latest_state().state, DockingState.IDLE, "not IDLE after dock abort")
        self.assertTrue(after and all(c.linear.x == 0 and c.linear.y == 0 and c.angular.z == 0 for c in after),
                        "non-zero cmd_vel after dock abort")
        print("closed_loop_check: dock abort: %s; dock start: %s" % (abort.lines[-1], first.lines[-1]), flush=True)

    def check_client_ends(self):
        """The second `dock start` ends DOCKED (its last line, exit 0); watch saw every end."""
        code = self.docking.finish(30.0)
        self.assertEqual(code, 0, "dock start:\n" + self.docking.text())
        self.assertTrue(self.docking.lines[-1].startswith("dock: DOCKED after"), self.docking.text())
        time.sleep(1.0)
        self.watch.finish(10.0, interrupt=True)
        watched = self.watch.lines
        states = [m.group(1) for m in (STATE_LINE.match(line) for line in watched) if m]
        self.assertIn("DOCKED", states, "dock watch printed no DOCKED line:\n" + self.watch.text())
        self.assertTrue(any(l.startswith("dock: DOCKED after") for l in watched), self.watch.text())
        self.assertTrue(any(l.startswith("dock: ABORTED after") for l in watched), self.watch.text())
        print("closed_loop_check: %s" % self.docking.lines[-1], flush=True)

    def test_closed_loop(self):
        mode = rospy.get_param("~mode")
        if mode == "dock":
            self.check_dock()
        elif mode == "lost":
            self.check_lost()
        else:
            self.fail("unknown ~mode %s" % mode)

    def check_dock(self):
        timeout = rospy.get_param("~timeout_s", 240.0)
        # The probe tip from the one home of the robot's geometry (robot.yaml, loaded for the planner).
        probe_x = rospy.get_param("/planner/robot/chaser/docking_probe_x_m")
        max_pos = rospy.get_param("~max_position_error_m", 0.01)
        max_yaw = rospy.get_param("~max_yaw_error_deg", 1.0)
        t0 = self.check_idle_then_start(self.wait_clock())
        docked = None
        visited = []
        while not rospy.is_shutdown() and rospy.get_time() - t0 < timeout:
            with self.lock:
                for _, s in self.states[len(visited):]:
                    visited.append(s)
                    if s.state == DockingState.DOCKED and docked is None:
                        docked = s
            if docked is not None:
                break
            rospy.sleep(0.2)
        names = []
        for s in visited:
            if not names or names[-1] != s.state_name:
                names.append(s.state_name)
        last = visited[-1] if visited else None
        self.assertIsNotNone(docked, "not DOCKED within %.0f s (sim); states %s; last: %s" % (
            timeout, " -> ".join(names), last.reason if last else "no docking/state"))
        (cx, cy, cyaw), (px, py, pyaw) = self.truth(docked.header.stamp)
        tip_err = math.hypot(cx + probe_x * math.cos(cyaw) - px, cy + probe_x * math.sin(cyaw) - py)
        yaw_err = math.degrees(abs(wrap(cyaw - (pyaw + math.pi))))
        result = "closed_loop_check: DOCKED at %.1f s (sim), true tip error %.1f mm, yaw %.2f deg; %s" % (
            docked.header.stamp.to_sec() - t0, 1000 * tip_err, yaw_err, " -> ".join(names))
        rospy.loginfo(result)
        print(result, flush=True)  # also in the test's XML result (system-out), for CI logs
        self.assertLessEqual(tip_err, max_pos, "true probe-tip error %.1f mm > %.1f mm" % (1000 * tip_err, 1000 * max_pos))
        self.assertLessEqual(yaw_err, max_yaw, "true yaw error %.2f deg > %.2f deg" % (yaw_err, max_yaw))
        # The action's result says so, and the planner is IDLE (zero velocity) afterwards.
        if rospy.get_param("~client", False):
            self.check_client_ends()
        else:
            self.assertTrue(self.client.wait_for_result(rospy.Duration(10.0)), "no action result after DOCKED")
            result = self.client.get_result()
            self.assertEqual(result.outcome, DockResult.DOCKED, "action result %d: %s" % (result.outcome, result.reason))
        rospy.sleep(1.0)
        self.assertEqual(self.latest_state().state, DockingState.IDLE, "not IDLE after the docking ended")

    def check_lost(self):
        lose_after = rospy.get_param("~lose_after_s", 4.0)
        timeout = rospy.get_param("~timeout_s", 90.0)
        hold_to_search_max = rospy.get_param("~hold_to_search_max_s", 10.0)
        t0 = self.check_idle_then_start(self.wait_clock())
        # 1. Wait for APPROACH on the relayed estimates, then cut them after lose_after_s.
        approach_t = None
        while rospy.get_time() - t0 < timeout:
            s = self.latest_state()
            if s is not None and s.state == DockingState.APPROACH and approach_t is None:
                approach_t = rospy.get_time()
            # Cut while the planner is approaching on a visible target (not in a natural dropout).
            if (approach_t is not None and rospy.get_time() - approach_t >= lose_after and
                    s.state == DockingState.APPROACH and s.target_visible):
                break
            rospy.sleep(0.05)
        self.assertIsNotNone(approach_t, "the planner never reached APPROACH")
        self.assertEqual(self.latest_state().state, DockingState.APPROACH,
                         "not in APPROACH when the target is made to vanish: %s" % self.latest_state().reason)
        self.relaying = False
        lost_t = rospy.get_time()
        with self.lock:
            n0 = len(self.states)
        # Chaser moving before the loss (a real mid-approach).
        moving = [c for t, c in self.cmds if t > lost_t - 1.0 and t <= lost_t]
        self.assertTrue(any(abs(c.linear.x) + abs(c.linear.y) > 1e-3 for c in moving),
                        "the chaser was not moving before the target vanished")
        # 2. HOLD, then SEARCH.
        hold_t = search_t = None
        settle = 0.3
        scanned = n0  # each state message is checked once (a rescan would test APPROACH cycles against HOLD)
        while rospy.get_time() - lost_t < timeout and search_t is None:
            with self.lock:
                fresh = self.states[scanned:]
                scanned += len(fresh)
                for t, s in fresh:
                    if s.header.stamp.to_sec() < lost_t + settle:
                        continue  # cycles that may still have seen estimates in flight at the cut
                    if hold_t is None and s.state == DockingState.HOLD:
                        hold_t = t
                    if hold_t is not None and search_t is None and s.state == DockingState.SEARCH:
                        search_t = t
                    if hold_t is None:
                        self.assertIn(s.state, (DockingState.APPROACH,),
                                      "left APPROACH for %s, not HOLD: %s" % (s.state_name, s.reason))
                    elif search_t is None:
                        self.assertEqual(s.state, DockingState.HOLD, "HOLD went to %s, not SEARCH: %s; "
                                         "last estimate relayed %.2f s after the cut (stamp %.2f s before it); %s"
                                         % (s.state_name, s.reason, self.last_relayed[0] - lost_t,
                                            lost_t - self.last_relayed[1], self.timeline(n0, lost_t)))
            rospy.sleep(0.05)
        self.assertIsNotNone(hold_t, "no HOLD after the target vanished")
        self.assertIsNotNone(search_t, "no SEARCH within %.0f s after HOLD" % timeout)
        self.assertLess(search_t - hold_t, hold_to_search_max, "HOLD lasted %.1f s" % (search_t - hold_t))
        self.assertLess(hold_t - lost_t, 2.0, "HOLD only %.1f s after the loss" % (hold_t - lost_t))
        # 3. Zero cmd_vel from HOLD (plus one control cycle of slack for topic ordering) until SEARCH
        #    starts turning (its standing wait included): kSearchWaitS after SEARCH began.
        search_wait = rospy.get_param("~standing_wait_s", 2.0)
        rospy.sleep(search_wait + 0.5)
        with self.lock:
            between = [(t, c) for t, c in self.cmds if hold_t + 0.1 < t < search_t + search_wait - 0.2]
        self.assertGreater(len(between), 10, "too few cmd_vel between HOLD and SEARCH")
        for t, c in between:
            self.assertTrue(c.linear.x == 0.0 and c.linear.y == 0.0 and c.angular.z == 0.0,
                            "non-zero cmd_vel %.3f %.3f %.3f at %.2f s after HOLD" % (
                                c.linear.x, c.linear.y, c.angular.z, t - hold_t))
        # The chaser (truth) stands still once the motors have spun down (0.5 s), until SEARCH turns.
        a = self.truth(rospy.Time.from_sec(hold_t + 0.6))[0]
        b = self.truth(rospy.Time.from_sec(search_t))[0]
        self.assertLess(math.hypot(a[0] - b[0], a[1] - b[1]), 0.005, "the chaser moved while holding")
        rospy.loginfo("closed_loop_check: lost at %.1f s, HOLD after %.2f s, SEARCH after %.2f s more, "
                      "%d zero cmd_vel in between", lost_t - t0, hold_t - lost_t, search_t - hold_t, len(between))


if __name__ == "__main__":
    faulthandler.register(signal.SIGUSR1)  # kill -USR1 <pid>: where a hung check is waiting
    rostest.rosrun(PKG, "closed_loop_check", ClosedLoopCheck, sys.argv)
