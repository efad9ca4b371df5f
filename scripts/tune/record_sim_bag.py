#!/usr/bin/env python3
"""Records a short bag from the simulator, with its truth, for tuning (docs/TUNING.md, issue 13).

    record_sim_bag.py --scenario translating_2m --duration 8 --out /tmp/tune/translating_2m.bag

The simulator (no perception: the bag is to be replayed through perception; --dock: the closed loop
docking from the start, the right camera then at the block matcher's rate as in any live docking) runs
on a master of its own; once its cameras publish, launch/record.launch records `duration` seconds of sim
time, with the simulator's truth (in record.launch's list), and the bag is moved to --out. The
replay_lossless rostest records its bag with it. About 7 MB per second of sim time with 15 Hz cameras
and JPEG images (record.launch's default), 31 MB raw (--images raw).
"""
import argparse
import glob
import os
import pathlib
import shutil
import subprocess
import sys
import tempfile
import time

sys.path.insert(0, str(pathlib.Path(__file__).resolve().parent))
import launch_runner  # noqa: E402

ROOT = pathlib.Path(__file__).resolve().parents[2]


def wait_for_cameras(env, timeout_s):
    """The recorder's duration counts from its own start on the sim clock: it must start after the
    cameras do, or the bag begins with seconds of nothing. rostopic fails at once while the master is not
    up yet, so it is asked again until then."""
    deadline = time.time() + timeout_s
    while subprocess.call(["rostopic", "echo", "-n", "1", "/stereo/left/camera_info"], env=env,
                          stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL, timeout=timeout_s) != 0:
        if time.time() > deadline:
            raise RuntimeError("the simulator's cameras did not start within %.0f s" % timeout_s)
        time.sleep(1.0)


def record(scenario, duration_s, rate_hz, real_time_factor, out_path, images=None, dock=False):
    """Runs the simulator and record.launch; returns the recorded bag moved to out_path. images: passed
    to record.launch as images:= when given (raw, compressed, both), else its default. dock: the closed
    loop (perception, planner) with a docking goal from the start, instead of the cameras alone."""
    work = tempfile.mkdtemp(prefix="record_sim_bag_")
    port = launch_runner.free_port()
    env = dict(os.environ, ROS_MASTER_URI="http://127.0.0.1:%d" % port)
    sim_log = open(os.path.join(work, "sim.log"), "w")
    sim = subprocess.Popen(
        ["roslaunch", "-p", str(port), str(ROOT / "launch" / "sim.launch"), "scenario:=" + scenario,
         "real_time_factor:=%g" % real_time_factor, "camera_rate_hz:=%g" % rate_hz,
         "dock:=true" if dock else "perception:=false", "output:=log"],
        env=env, stdout=sim_log, stderr=subprocess.STDOUT, start_new_session=True)
    try:
        wait_for_cameras(env, 240.0)
        with open(os.path.join(work, "record.log"), "w") as log:
            recorder = subprocess.Popen(["roslaunch", str(ROOT / "launch" / "record.launch"),
                                         "path:=" + os.path.join(work, "rec"), "duration:=%gs" % duration_s]
                                        + (["images:=" + images] if images else []),
                                        env=env, stdout=log, stderr=subprocess.STDOUT, start_new_session=True)
            try:
                rc = recorder.wait(timeout=60 + 20 * duration_s / real_time_factor)
            finally:
                launch_runner.stop(recorder)  # on a timeout: the launch and its rosbag record, not only roslaunch
    finally:
        launch_runner.stop(sim)
        sim_log.close()
    bags = glob.glob(os.path.join(work, "rec_*.bag"))
    if rc != 0 or len(bags) != 1:
        raise RuntimeError("record.launch failed (exit %s, bags %s); logs in %s" % (rc, bags, work))
    pathlib.Path(out_path).parent.mkdir(parents=True, exist_ok=True)
    shutil.move(bags[0], out_path)
    shutil.rmtree(work, ignore_errors=True)
    return out_path


def main():
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--scenario", default="translating_2m", help="config/scenarios/<name>.yaml")
    parser.add_argument("--duration", type=float, default=8.0, help="seconds of sim time to record")
    parser.add_argument("--rate", type=float, default=15.0, help="camera rate, Hz (the robot's)")
    parser.add_argument("--real-time-factor", type=float, default=0.3,
                        help="sim seconds per wall second: low enough that the recorder keeps every image")
    parser.add_argument("--images", choices=("raw", "compressed", "both"),
                        help="record.launch images:= (default: record.launch's, compressed); raw for bit-exact frames, "
                             "both to measure what compression costs (tune_replay.py --images raw,compressed)")
    parser.add_argument("--dock", action="store_true",
                        help="closed loop: perception and the planner run and dock from the start (else the "
                             "cameras alone: the scenario's own motion)")
    parser.add_argument("--out", required=True, help="the bag to write (keep it out of the repository)")
    args = parser.parse_args()
    if not (ROOT / "config" / "scenarios" / (args.scenario + ".yaml")).exists():
        parser.error("no scenario %s in %s" % (args.scenario, ROOT / "config" / "scenarios"))
    try:
        path = record(args.scenario, args.duration, args.rate, args.real_time_factor, args.out, args.images,
                      args.dock)
    except (RuntimeError, subprocess.TimeoutExpired) as err:
        sys.exit("record_sim_bag: %s" % err)
    print("record_sim_bag: wrote %s (%.1f MB)" % (path, os.path.getsize(path) / 1e6))


if __name__ == "__main__":
    main()
