#!/usr/bin/env python3
"""The operator's client, again and again (issue 54): `rosrun docking_planner dock start`, then, once the
chaser moves, `rosrun docking_planner dock abort`, N rounds, on the simulator or on a replay, each run on a
master of its own. Per round it checks that the start reached the planner (it left IDLE) and ended with its
`dock: ABORTED` line, and that the abort exited 0 saying the goal was cancelled with the planner IDLE; and
it measures, on the wall clock, when the wheels stopped after the cancel reached the planner (this node
receives the cancel message as the planner does; when it missed it, the planner's first IDLE state) and
after the abort command was started (as if typed).
Wheels stopped: in the simulator every wheel slower than 0.5 rad/s (1.2 cm/s at the rim: robot_bench's
bound) on omni_base's wheels/state; in a replay (no base) the planner's first zero cmd_vel.

  source devel/setup.bash
  scripts/client_trials.py --rounds 20                                  # sim.launch (default scene, no end)
  scripts/client_trials.py --rounds 20 --replay bags/far_approach.bag   # replay.launch loop:=true

Prints one line per round and a summary; exit status 0 when every round succeeded. It does not load the
machine itself: run it beside `yes > /dev/null` hogs to measure a busy machine.
"""
import argparse
import os
import pathlib
import shutil
import subprocess
import sys
import threading
import time

sys.path.insert(0, str(pathlib.Path(__file__).resolve().parent / "tune"))
import launch_runner  # noqa: E402
from yaml_line_edit import set_key  # noqa: E402

ROOT = pathlib.Path(__file__).resolve().parents[1]
STOPPED_RAD_S = 0.5


class Watch:
    """What the trials need to see, with wall-clock receipt times."""

    def __init__(self, replay):
        import rospy
        from actionlib_msgs.msg import GoalID
        from docking_msgs.msg import DockingState, WheelState
        from geometry_msgs.msg import Twist
        self.lock = threading.Lock()
        self.states, self.cancels, self.motion = [], [], []  # (wall, value)
        self.DockingState = DockingState
        rospy.Subscriber("docking/state", DockingState, lambda m: self.add(self.states, m.state), queue_size=50)
        rospy.Subscriber("docking/dock/cancel", GoalID, lambda m: self.add(self.cancels, m), queue_size=10)
        if replay:  # no base: the planner's command is what would move it
            rospy.Subscriber("cmd_vel", Twist, lambda m: self.add(
                self.motion, abs(m.linear.x) + abs(m.linear.y) + abs(m.angular.z) > 0.0), queue_size=50)
        else:
            rospy.Subscriber("wheels/state", WheelState, lambda m: self.add(
                self.motion, max((abs(v) for v in m.velocity), default=0.0) > STOPPED_RAD_S), queue_size=50)

    def add(self, into, value):
        with self.lock:
            into.append((time.time(), value))

    def since(self, into, wall):
        with self.lock:
            return [(t, v) for t, v in into if t >= wall]

    def wait(self, condition, timeout_s):
        deadline = time.time() + timeout_s
        while time.time() < deadline:
            if condition():
                return True
            time.sleep(0.02)
        return False


def client(*args):
    return subprocess.Popen(["rosrun", "docking_planner", "dock"] + list(args), stdout=subprocess.PIPE,
                            stderr=subprocess.STDOUT, text=True)


def finish(proc, timeout_s):
    """The output of a client process; killed (and its output so far) when it outlives timeout_s."""
    try:
        return proc.communicate(timeout=timeout_s)[0]
    except subprocess.TimeoutExpired:
        proc.kill()
        return proc.communicate()[0] + "\n(killed after %.0f s)" % timeout_s


def one_round(watch, number):
    """Returns (ok, text, seconds from the cancel's arrival to stopped, from the abort's start to stopped)."""
    t0 = time.time()
    start = client("start")
    moving = watch.wait(lambda: any(v for _, v in watch.since(watch.motion, t0)) and any(
        s != watch.DockingState.IDLE for _, s in watch.since(watch.states, t0)), 90.0)
    if not moving:
        start.kill()
        return False, "round %d: the chaser never moved after dock start: %s" % (number, start.communicate()[0]), None, None
    typed = time.time()
    abort = client("abort")
    abort_out, start_out = finish(abort, 60.0), finish(start, 30.0)
    time.sleep(1.0)  # the wheels' deceleration, seen whole
    # When the cancel reached the planner: this node hears it as the planner does, unless the abort published
    # before this node's connection was up (it waits for the planner's only); then the planner's first IDLE.
    cancels = watch.since(watch.cancels, typed)
    idle = [(t, s) for t, s in watch.since(watch.states, typed) if s == watch.DockingState.IDLE]
    reached = cancels[0][0] if cancels else idle[0][0] if idle else None
    after = watch.since(watch.motion, reached if reached is not None else typed)
    turning = [t for t, v in after if v]
    stopped_at = (max(turning) if turning else after[0][0] if after else None)
    problems = []
    if abort.returncode != 0 or "dock: ABORTED: docking goal" not in abort_out:
        problems.append("abort: exit %s: %s" % (abort.returncode, abort_out.strip()))
    start_last = (start_out.strip().splitlines() or [""])[-1]
    if start.returncode != 1 or not start_last.startswith("dock: ABORTED after"):
        problems.append("start: exit %s: %s" % (start.returncode, start_last))
    if reached is None:
        problems.append("the planner never reported IDLE")
    if stopped_at is None or (after and after[-1][1]):
        problems.append("not stopped")
    if problems:
        return False, "round %d: %s" % (number, "; ".join(problems)), None, None
    from_cancel = max(0.0, stopped_at - reached)
    from_typed = stopped_at - typed
    return True, "round %d: ok: stopped %.2f s after the cancel reached the planner, %.2f s after dock abort " \
                 "started (%s)" % (number, from_cancel, from_typed, abort_out.strip().splitlines()[-1]), from_cancel, from_typed


def percentile(values, q):
    ordered = sorted(values)
    return ordered[min(len(ordered) - 1, int(round(q * (len(ordered) - 1))))]


def main():
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--rounds", type=int, default=20)
    parser.add_argument("--replay", metavar="BAG", help="replay.launch loop:=true of this bag instead of sim.launch")
    parser.add_argument("--scenario", default="default", help="sim.launch scenario")
    parser.add_argument("--out", default=str(ROOT / "results" / "client_trials"))
    args = parser.parse_args()
    out = pathlib.Path(args.out)
    out.mkdir(parents=True, exist_ok=True)
    port = launch_runner.free_port()
    os.environ["ROS_MASTER_URI"] = "http://127.0.0.1:%d" % port
    if args.replay:
        launch = [str(ROOT / "launch" / "replay.launch"), "bag:=" + str(pathlib.Path(args.replay).resolve()),
                  "loop:=true", "dock:=false"]
    else:  # the scenario without its end (duration_s 0): the rounds take longer than its 300 s
        scenario = out / (args.scenario + ".yaml")
        shutil.copy(ROOT / "config" / "scenarios" / (args.scenario + ".yaml"), scenario)
        set_key(str(scenario), "scenario.duration_s", "0.0")
        launch = [str(ROOT / "launch" / "sim.launch"), "scenario_file:=" + str(scenario)]
    with open(out / "launch.log", "w") as log:
        proc = subprocess.Popen(["roslaunch", "-p", str(port)] + launch + ["output:=log"], stdout=log,
                                stderr=subprocess.STDOUT, start_new_session=True)
    try:
        import rospy
        while subprocess.call(["rostopic", "echo", "-n", "1", "/clock"], stdout=subprocess.DEVNULL,
                              stderr=subprocess.DEVNULL) != 0:
            time.sleep(1.0)
        rospy.init_node("client_trials", anonymous=True, disable_signals=True)
        watch = Watch(bool(args.replay))
        time.sleep(5.0)  # perception up
        results = []
        for number in range(1, args.rounds + 1):
            ok, text, from_cancel, from_typed = one_round(watch, number)
            print(text, flush=True)
            results.append((ok, from_cancel, from_typed))
    finally:
        launch_runner.stop(proc)
    good = [r for r in results if r[0]]
    print("client_trials: %s: %d of %d rounds: dock start and dock abort both succeeded" % (
        "replay of " + args.replay if args.replay else "sim.launch " + args.scenario, len(good), len(results)))
    if good:
        for name, index in (("after the cancel reached the planner", 1), ("after dock abort was started", 2)):
            values = [r[index] for r in good]
            print("client_trials: wheels stopped %s: median %.2f s, p95 %.2f s, max %.2f s" % (
                name, percentile(values, 0.5), percentile(values, 0.95), max(values)))
    return 0 if len(good) == len(results) else 1


if __name__ == "__main__":
    sys.exit(main())
