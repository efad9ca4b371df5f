#!/usr/bin/env python3
"""Screenshots of rviz (config/docking.rviz) during a simulated docking, headless (issue 14): how to see
what a user sees without a screen, and where the README's pictures come from.

Starts Xvfb, then sim.launch rviz:=true dock:=true (or, with --replay BAG, replay.launch bag:=BAG
rviz:=true, looping) on a master of its own, and saves the whole screen (ImageMagick's `import -window
root`) at each moment asked for: seconds since the simulation started, or into the bag ("12.5"), or a
planner state, taken when the planner first enters it ("ALIGN", "DOCKED"; --settle-s later, so that rviz
has drawn it). Each file is named by the moment it shows, measured when it was taken:
<scenario or bag>[_<state>]_t<seconds>s.png, and for a replay _pass<N> (the bag loops while rviz starts;
a time is taken in the first pass that reaches it with rviz up). Ends when every moment is taken or
--timeout-s (wall) passes.

  source devel/setup.bash
  scripts/rviz_screenshots.py [--scenario default] [--at 2,ALIGN,DOCKED] [--out results/rviz]
  scripts/rviz_screenshots.py --replay bags/near_approach.bag --at 4 --out results/rviz
"""
import argparse
import os
import pathlib
import subprocess
import sys
import time

sys.path.insert(0, str(pathlib.Path(__file__).resolve().parent / "tune"))
import launch_runner  # noqa: E402

ROOT = pathlib.Path(__file__).resolve().parents[1]


def parse_args():
    p = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    p.add_argument("--scenario", default="default")
    p.add_argument("--replay", metavar="BAG", help="replay this bag (replay.launch) instead of simulating")
    p.add_argument("--at", default="2,ALIGN,DOCKED", help="sim seconds and/or planner states, comma separated")
    p.add_argument("--out", default=str(ROOT / "results" / "rviz"))
    p.add_argument("--real-time-factor", type=float, default=0.3)
    p.add_argument("--settle-s", type=float, default=0.3,
                   help="sim seconds after a state is entered (DOCKED lasts one planner cycle before IDLE)")
    p.add_argument("--size", default="1500x900", help="screen size (docking.rviz's window is 1500x900)")
    p.add_argument("--display", default=":97")
    p.add_argument("--timeout-s", type=float, default=900.0)
    return p.parse_args()


class Moments:
    """What to capture: times, and states turned into times when the planner enters them. Times count from
    the start of the simulation, or of the bag's pass (pass_s: a replay's pass length; 0: no loop)."""

    def __init__(self, text, settle_s, pass_s=0.0):
        self.pending = {}   # label ("" for a time, else the state) -> time to capture at (None: waiting)
        self.settle_s = settle_s
        self.pass_s = pass_s
        for item in (x.strip() for x in text.split(",") if x.strip()):
            try:
                self.pending["%.1f" % float(item)] = float(item)
            except ValueError:
                self.pending[item.upper()] = None

    def into_pass(self, now_s):
        """(pass number from 1, seconds into it)."""
        if self.pass_s <= 0.0:
            return 1, now_s
        return int(now_s // self.pass_s) + 1, now_s % self.pass_s

    def on_state(self, state_name, now_s):
        if self.pending.get(state_name, 0.0) is None:
            self.pending[state_name] = self.into_pass(now_s)[1] + self.settle_s

    def due(self, now_s):
        """The moments to take now: their time reached (in a replay: in this pass, not more than a second
        ago; a later pass brings it again). The file name says when it was really taken."""
        into = self.into_pass(now_s)[1]
        late_ok = float("inf") if self.pass_s <= 0.0 else 1.0
        return [label for label, t in self.pending.items() if t is not None and t <= into < t + late_ok]

    def file_name(self, prefix, label, now_s):
        number, into = self.into_pass(now_s)
        state = "" if label[:1].isdigit() else "_" + label
        return "%s%s_t%04.1fs%s.png" % (prefix, state, into, "_pass%d" % number if self.pass_s > 0.0 else "")


def main():
    args = parse_args()
    out = pathlib.Path(args.out)
    out.mkdir(parents=True, exist_ok=True)
    pass_s = 0.0
    if args.replay:
        import rosbag
        with rosbag.Bag(args.replay) as bag:  # replay_paced's pass: the bag's length and a 0.1 s gap
            pass_s = bag.get_end_time() - bag.get_start_time() + 0.1
    moments = Moments(args.at, args.settle_s, pass_s)
    # GLX on and Mesa's software renderer: without them rviz (OGRE) dies at start-up (SIGSEGV) on Xvfb.
    xvfb = subprocess.Popen(["Xvfb", args.display, "-screen", "0", args.size + "x24", "+extension", "GLX",
                             "-nolisten", "tcp"],
                            stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL, start_new_session=True)
    port = launch_runner.free_port()
    env = dict(os.environ, DISPLAY=args.display, LIBGL_ALWAYS_SOFTWARE="1",
               ROS_MASTER_URI="http://127.0.0.1:%d" % port)
    os.environ.update(ROS_MASTER_URI=env["ROS_MASTER_URI"])
    if args.replay:
        # Looping (the clock rising pass after pass): rviz starts slowly, and a moment past by then is taken
        # in a later pass, on a live view.
        launch = [str(ROOT / "launch" / "replay.launch"), "bag:=" + str(pathlib.Path(args.replay).resolve()),
                  "loop:=true"]
        args.scenario = pathlib.Path(args.replay).stem  # names the pictures
    else:
        launch = [str(ROOT / "launch" / "sim.launch"), "scenario:=" + args.scenario, "dock:=true",
                  "real_time_factor:=%g" % args.real_time_factor]
    sim = subprocess.Popen(["roslaunch", "-p", str(port)] + launch + ["rviz:=true", "output:=log"],
                           env=env, stdout=open(out / "launch.log", "w"), stderr=subprocess.STDOUT,
                           start_new_session=True)
    try:
        capture_all(moments, env, out, args)
    finally:
        launch_runner.stop(sim)
        xvfb.terminate()
        xvfb.wait(timeout=30)


# What docking.rviz subscribes to last: when rviz subscribes to all of them, its displays are up.
RVIZ_TOPICS = ("/docking/markers", "/perception/mono_visible/debug_image", "/perception/disparity/debug_image",
               "/perception/mono_ir/debug_image")


def wait_for_rviz(master, deadline, drawn_s=10.0):
    """Until rviz has subscribed to its last displays' topics, then drawn_s wall seconds for its first frames
    (software rendering on a busy machine is slow): a moment due earlier is taken then, not on the splash."""
    while time.time() < deadline:
        _, subscribers, _ = master.getSystemState()
        by_rviz = {topic for topic, nodes in subscribers if any(n.startswith("/rviz") for n in nodes)}
        if by_rviz.issuperset(RVIZ_TOPICS):
            time.sleep(drawn_s)
            return
        time.sleep(0.5)


def capture_all(moments, env, out, args):
    import rosgraph
    import rospy
    from docking_msgs.msg import DockingState
    # On the simulator's clock: /use_sim_time must be set before this node starts, and /clock running.
    master = rosgraph.Master("/rviz_screenshots")
    while not (master.is_online() and master.hasParam("/use_sim_time")):
        time.sleep(0.5)
    rospy.init_node("rviz_screenshots", anonymous=True, disable_signals=True)
    while rospy.Time.now().is_zero():
        time.sleep(0.1)
    clock_start_s = rospy.Time.now().to_sec()  # a simulation starts at 0, a replay at its bag's time
    rospy.Subscriber("/docking/state", DockingState,
                     lambda m: moments.on_state(m.state_name, rospy.Time.now().to_sec() - clock_start_s), queue_size=10)
    deadline = time.time() + args.timeout_s
    wait_for_rviz(master, deadline)
    while moments.pending and time.time() < deadline:
        now_s = rospy.Time.now().to_sec() - clock_start_s
        for label in moments.due(now_s):
            path = out / moments.file_name(args.scenario, label, now_s)
            subprocess.run(["import", "-window", "root", str(path)], env=env, check=True, timeout=60)
            print("rviz_screenshots: %s (%.1f s since the clock started)" % (path, now_s), flush=True)
            del moments.pending[label]
        time.sleep(0.1)
    if moments.pending:
        sys.exit("rviz_screenshots: not reached within %.0f s: %s" % (args.timeout_s, ", ".join(moments.pending)))


if __name__ == "__main__":
    main()
