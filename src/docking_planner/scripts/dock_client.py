#!/usr/bin/env python3
"""The operator's docking client (the planner's action server docking/dock, docking_msgs/Dock).

  rosrun docking_planner dock start [--time-budget S] [--search-timeout S] [--max-speed V] [--delay S]
      sends a goal, prints each state change (and the progress every 2 s), and ends with one line that
      names the outcome: `dock: DOCKED after T s: <errors>`, `dock: ABORTED ...` or `dock: FAILED ...: <cause>`.
      Exit status 0 when DOCKED, 1 otherwise. Ctrl-C cancels the docking and waits for the planner to
      confirm it (and so does this client dying: the planner ends a docking whose client is gone and stops
      the wheels). A planner that restarts mid-docking (respawned) loses the goal: it is sent again, with
      what is left of the time budget, so the docking resumes.
  rosrun docking_planner dock watch      prints each state change of whatever docking runs, and its end
  rosrun docking_planner dock abort      cancels every docking goal and waits until the planner reports no
      goal running and IDLE (zero velocity): exit status 0 then; 3, with a loud message, when that is not
      confirmed within --confirm-timeout (then use the e-stop). scripts/dock runs the C++ dock_abort for it
      (quick to start on a busy computer) and this Python client for start and watch.

Every wait is on the wall clock: under simulated time (/use_sim_time: sim.launch, replays) the client
first waits for /clock, then for the planner, at most --server-timeout seconds (0: for ever).
The e-stop (omni_base, topic e_stop) overrides everything; this client cannot release it.
"""
import os
import sys



import argparse  # noqa: E402
import math  # noqa: E402
import threading  # noqa: E402
import time  # noqa: E402

import rospy  # noqa: E402
from actionlib_msgs.msg import GoalID, GoalStatus, GoalStatusArray  # noqa: E402
from docking_msgs.msg import DockActionFeedback, DockActionResult, DockResult, DockingState  # noqa: E402

ACTION = "docking/dock"  # docking_msgs/names.h kDockAction
STATE_TOPIC = "docking/state"  # docking_msgs/names.h kDockingState
OUTCOMES = {getattr(DockResult, n): n for n in ("UNKNOWN", "DOCKED", "CANCELLED", "TIME_BUDGET", "TARGET_LOST",
                                               "CLIENT_GONE", "REJECTED", "SHUTDOWN", "PERCEPTION_LOST")}
STATES = {getattr(DockingState, n): n for n in
          ("SEARCH", "APPROACH", "ALIGN", "FINAL", "DOCKED", "HOLD", "ABORT", "IDLE")}
SOURCES = {0: "disparity", 1: "mono visible", 2: "mono IR", 3: "fused"}
RUNNING = (GoalStatus.PENDING, GoalStatus.ACTIVE, GoalStatus.PREEMPTING, GoalStatus.RECALLING)
E_STOP_HINT = "stop the robot with the e-stop: rostopic pub -1 /e_stop std_msgs/Bool true"
PROGRESS_EVERY_S = 2.0


def number(value, form, unit):
    """A value with its unit, or `?` for an unknown (NaN) one."""
    return "?" if value != value else (form % value) + unit


def describe(state, elapsed):
    """One line: elapsed time, state, source, range and errors (`?` where the planner does not know)."""
    text = "%7s  %-8s" % ("-" if elapsed is None else "%.1f s" % elapsed, STATES.get(state.state, str(state.state)))
    if state.range_m == state.range_m:  # a target is held
        text += "  %s  range %s  lateral %s  yaw %s" % (
            SOURCES.get(state.estimate_source, "?") if state.target_visible else "not seen",
            number(state.range_m, "%.2f", " m"), number(state.lateral_error_m, "%+.3f", " m"),
            number(math.degrees(state.yaw_error_rad), "%+.2f", " deg"))
    return text + "  " + state.reason


def outcome_line(result):
    """The one line that ends a docking: DOCKED with its errors, ABORTED, or FAILED with the cause."""
    name = OUTCOMES.get(result.outcome, str(result.outcome))
    if result.outcome == DockResult.DOCKED:
        return "dock: DOCKED after %.1f s: %s" % (result.duration_s, result.reason)
    if result.outcome == DockResult.CANCELLED:
        return "dock: ABORTED after %.1f s: %s" % (result.duration_s, result.reason)
    return "dock: FAILED after %.1f s: %s: %s" % (result.duration_s, name, result.reason)


class StatePrinter:
    """Prints a line at each state change and every PROGRESS_EVERY_S seconds of a state; after a docking's
    end (end()), the IDLE that follows is that end, already said, and is not printed."""

    def __init__(self):
        self.lock = threading.Lock()
        self.last_state = None
        self.last_print = -1e9
        self.goal_start = None  # ROS time the running docking started (None: none known)
        self.quiet_idle = False
        self.enabled = True

    def elapsed(self, state):
        if self.goal_start is None or state.state == DockingState.IDLE:
            return None
        return max(0.0, state.header.stamp.to_sec() - self.goal_start)

    def __call__(self, state):
        with self.lock:
            if not self.enabled:
                return
            changed = state.state != self.last_state
            now = time.time()
            # The IDLE before a goal (start), and the IDLE that ends a docking: its outcome line says it.
            if state.state == DockingState.IDLE and (self.quiet_idle or self.goal_start is not None):
                return
            if state.state != DockingState.IDLE:
                self.quiet_idle = False
            if changed or (state.state != DockingState.IDLE and now - self.last_print >= PROGRESS_EVERY_S):
                print(describe(state, self.elapsed(state)), flush=True)
                self.last_state, self.last_print = state.state, now

    def end(self, result, stop=False):
        """A docking ended: its last state (DOCKED lasts one cycle and may not have been seen) and the
        outcome line. stop: print nothing more afterwards."""
        with self.lock:
            final = result.final_state
            if final.header.stamp.to_sec() > 0.0 and final.state != self.last_state and final.state != DockingState.IDLE:
                print(describe(final, result.duration_s), flush=True)
            print(outcome_line(result), flush=True)
            self.last_state = DockingState.IDLE
            self.quiet_idle = True
            self.goal_start = None
            self.enabled = not stop


def wait_until(condition, deadline, step_s=0.02):
    """Waits on the wall clock until condition() or the deadline (None: none); returns condition()."""
    while not condition():
        if rospy.is_shutdown() or (deadline is not None and time.time() >= deadline):
            return condition()
        time.sleep(step_s)
    return True


def wait_for_clock(deadline):
    """Under /use_sim_time, waits (wall clock) for the first /clock: before it ROS time is 0, and a deadline
    or a goal stamp taken from it is wrong. Returns False at the deadline."""
    if not rospy.get_param("/use_sim_time", False):
        return True
    if wait_until(lambda: not rospy.get_rostime().is_zero(), deadline):
        return True
    print("dock: no /clock within the wait (use_sim_time is set: is the simulator or the replay running?)",
          file=sys.stderr, flush=True)
    return False


def server_connected(client):
    """actionlib's own test of a connected server (ActionClient.wait_for_server), without its ROS-time
    deadline: the server's status heard, and goal, cancel, result and feedback connected to it."""
    ac = client.action_client
    if not ac.last_status_msg:
        return False
    server = ac.last_status_msg._connection_header["callerid"]
    return (ac.pub_goal.impl.has_connection(server) and ac.pub_cancel.impl.has_connection(server) and
            any(c.callerid_pub == server for c in ac.result_sub.impl.connections) and
            any(c.callerid_pub == server for c in ac.feedback_sub.impl.connections))


def deadline_of(args):
    return None if args.server_timeout <= 0.0 else time.time() + args.server_timeout


def no_server(args):
    print("dock: no docking action server on %s within %.0f s of wall time (is the planner running? "
          "--server-timeout 0 waits for ever)" % (rospy.resolve_name(ACTION), args.server_timeout),
          file=sys.stderr, flush=True)
    return 2


# A planner that restarted (respawned after a crash) no longer knows the goal: actionlib reports it LOST.
# The client sends it again, this many times at most, so that the docking resumes from where the chaser is.
MAX_GOAL_RESENDS = 5


def start(args):
    import actionlib  # start only: abort must be quick to start
    from docking_msgs.msg import DockAction, DockGoal

    if args.delay > 0.0:
        print("dock: sending the goal in %.0f s" % args.delay, flush=True)
        time.sleep(args.delay)
    deadline = deadline_of(args)
    if not wait_for_clock(deadline):
        return 2
    client = actionlib.SimpleActionClient(ACTION, DockAction)
    printer = StatePrinter()
    printer.quiet_idle = True  # the IDLE before the goal
    rospy.Subscriber(STATE_TOPIC, DockingState, printer, queue_size=50)
    if not wait_until(lambda: server_connected(client), deadline):
        return no_server(args)
    started = rospy.get_time()
    done = threading.Event()
    result = None
    try:
        for attempt in range(MAX_GOAL_RESENDS + 1):
            budget = args.time_budget
            if budget > 0.0:
                budget = max(budget - (rospy.get_time() - started), 1e-3)
            done.clear()
            printer.goal_start = rospy.get_time()
            client.send_goal(DockGoal(time_budget_s=budget, search_timeout_s=args.search_timeout,
                                      max_speed_mps=args.max_speed), done_cb=lambda *_: done.set())
            print("dock: goal sent to %s" % rospy.resolve_name(ACTION), flush=True)
            wait_until(done.is_set, None, 0.05)
            if rospy.is_shutdown() or client.get_state() != GoalStatus.LOST or attempt == MAX_GOAL_RESENDS:
                break
            print("dock: the planner lost the goal (it restarted); waiting for it and sending the goal again",
                  file=sys.stderr, flush=True)
            if not wait_until(lambda: server_connected(client), deadline_of(args)):
                break
        result = client.get_result()
    except KeyboardInterrupt:
        return cancel_started(client, printer, done, args)
    if result is None:
        print("dock: FAILED: no result from the planner (goal %s)" % GoalStatus.to_string(client.get_state()),
              flush=True)
        return 1
    printer.end(result, stop=True)
    return 0 if result.outcome == DockResult.DOCKED else 1


def cancel_started(client, printer, done, args):
    """Ctrl-C in `dock start`: cancels the goal and waits (wall clock) for the planner's result."""
    print("dock: Ctrl-C: cancelling the docking", flush=True)
    client.cancel_goal()
    try:
        confirmed = wait_until(done.is_set, time.time() + args.confirm_timeout, 0.02)
    except KeyboardInterrupt:
        confirmed = done.is_set()
    result = client.get_result() if confirmed else None
    if result is None:
        print("dock: ABORT NOT CONFIRMED: the planner did not answer the cancel within %.0f s; %s" % (
            args.confirm_timeout, E_STOP_HINT), file=sys.stderr, flush=True)
        return 3
    printer.end(result, stop=True)
    return 1


def watch(_args):
    printer = StatePrinter()

    def on_feedback(m):
        printer.goal_start = m.header.stamp.to_sec() - m.feedback.elapsed_s

    rospy.Subscriber(ACTION + "/feedback", DockActionFeedback, on_feedback, queue_size=10)
    rospy.Subscriber(ACTION + "/result", DockActionResult, lambda m: printer.end(m.result), queue_size=10)
    rospy.Subscriber(STATE_TOPIC, DockingState, printer, queue_size=50)
    print("dock: watching %s (Ctrl-C to stop watching; the docking goes on)" % rospy.resolve_name(ACTION), flush=True)
    try:
        while not rospy.is_shutdown():
            time.sleep(0.2)
    except KeyboardInterrupt:
        pass
    return 0


def master_reachable(args):
    """Waits (wall clock, at most --server-timeout) for the ROS master: rospy would keep retrying it for ever."""
    import rosgraph
    master = rosgraph.Master("/dock_client")
    return wait_until(master.is_online, deadline_of(args), 0.1)


def main():
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--server-timeout", type=float, default=10.0,
                        help="wait this long (wall clock, s) for /clock and the planner; 0: for ever")
    parser.add_argument("--confirm-timeout", type=float, default=5.0,
                        help="abort, Ctrl-C: wait this long (wall clock, s) for the planner to confirm the cancel")
    sub = parser.add_subparsers(dest="command", required=True)
    p = sub.add_parser("start", help="start a docking and follow it to its end")
    p.add_argument("--time-budget", type=float, default=0.0, help="give up after this long (s); 0: no limit")
    p.add_argument("--search-timeout", type=float, default=0.0,
                   help="give up after searching, or holding with perception gone, this long (s); 0: the planner's")
    p.add_argument("--max-speed", type=float, default=0.0, help="linear speed cap (m/s); 0: the planner's")
    p.add_argument("--delay", type=float, default=0.0,
                   help="wait this long (wall clock, s) before sending the goal (bench mode: until its frames move)")
    sub.add_parser("watch", help="print each state change of the running docking, and its end")
    sub.add_parser("abort", help="cancel every docking goal and confirm the planner is IDLE")
    args = parser.parse_args(rospy.myargv()[1:])
    try:
        if not master_reachable(args):
            print("dock: no ROS master at %s within %.0f s of wall time" % (
                os.environ.get("ROS_MASTER_URI", "?"), args.server_timeout), file=sys.stderr, flush=True)
            return 2
        # Ctrl-C is ours (start cancels and waits for the planner's answer); rospy's handler would shut the
        # node down first.
        rospy.init_node("dock_client", anonymous=True, disable_signals=True)
        return {"start": start, "watch": watch}[args.command](args)
    except KeyboardInterrupt:  # before a goal was sent: nothing to cancel
        print("dock: interrupted before any goal was sent", file=sys.stderr, flush=True)
        return 130


if __name__ == "__main__":
    code = main()
    rospy.signal_shutdown("done")
    sys.stdout.flush()
    sys.stderr.flush()
    os._exit(code)  # rospy's threads may still retry a master that went away: they must not hold the exit
