#!/usr/bin/env python3
"""Records the sample bags of bags/ (bags/README.md) from one simulated docking, with the simulator's truth.

The simulator runs the still_3m scene (the port 3 m ahead, facing the chaser) in closed loop;
record.launch, exactly as a user runs it on the robot (images compressed, its default), records
  far_approach.bag   --seconds of sim time from the docking goal (sent once the recorder listens): the far
                     range (disparity detector) as the chaser sets off from 3 m;
  near_approach.bag  --seconds from the moment the docking port comes within --near-range-m of the left
                     camera: the monocular poses during the final approach.
Both add the truth topics (/sim/truth/stereo_left, /sim/truth/ir, /sim/truth/chaser). The cameras run at
--camera-rate-hz (5 Hz, the paper's monocular rate: 15 Hz would not fit 6 s into 20 MB). Each bag must
stay under --max-mb (20); the script fails otherwise.

  source devel/setup.bash; scripts/tune/record_sample_bags.py [--out-dir bags] [--seconds 6]
"""
import argparse
import glob
import math
import os
import pathlib
import shutil
import subprocess
import sys
import tempfile
import time

sys.path.insert(0, str(pathlib.Path(__file__).resolve().parent))
import launch_runner  # noqa: E402
from record_sim_bag import wait_for_cameras  # noqa: E402

REPO = str(pathlib.Path(__file__).resolve().parents[2])
LAUNCH = os.path.join(REPO, "launch")


def parse_args():
    p = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    p.add_argument("--out-dir", default=os.path.join(REPO, "bags"))
    p.add_argument("--scenario", default="still_3m")
    p.add_argument("--seconds", type=float, default=6.0, help="sim seconds per bag")
    p.add_argument("--camera-rate-hz", type=float, default=5.0)
    p.add_argument("--real-time-factor", type=float, default=0.5)
    p.add_argument("--near-range-m", type=float, default=1.3)
    p.add_argument("--max-mb", type=float, default=20.0)
    p.add_argument("--timeout-s", type=float, default=900.0, help="wall seconds for the whole recording")
    return p.parse_args()


def start_recording(env, path, seconds, log_dir, name):
    log = open(os.path.join(log_dir, name + ".log"), "w")
    return subprocess.Popen(["roslaunch", os.path.join(LAUNCH, "record.launch"), "path:=" + path,
                             "duration:=%gs" % seconds],  # the truth is in record.launch's list
                            env=env, stdout=log, stderr=subprocess.STDOUT, start_new_session=True)


def wait_until_recording(env, deadline):
    """Blocks until a recorder subscribes to the left camera's compressed images."""
    import rosgraph
    master = rosgraph.Master("/record_sample_bags", master_uri=env["ROS_MASTER_URI"])
    while time.time() < deadline:
        _, subscribers, _ = master.getSystemState()
        if any(topic == "/stereo/left/image_raw/compressed" and any(n.startswith("/record") for n in nodes)
               for topic, nodes in subscribers):
            return
        time.sleep(0.5)
    sys.exit("record_sample_bags: record.launch did not subscribe to the images")


def wait_for_port_within(range_m, deadline):
    """Blocks until the truth puts the docking port within range_m of the left camera."""
    import rospy
    from nav_msgs.msg import Odometry
    while time.time() < deadline and not rospy.is_shutdown():
        try:
            msg = rospy.wait_for_message("/sim/truth/stereo_left", Odometry, timeout=5.0)
        except rospy.ROSException:
            continue
        p = msg.pose.pose.position
        if math.sqrt(p.x * p.x + p.y * p.y + p.z * p.z) < range_m:
            return True
    return False


def finish(recorder, name, work, out_dir, max_mb, deadline):
    """Waits for one record.launch, moves its bag to out_dir/name.bag; returns its size in MB."""
    recorder.wait(timeout=max(1.0, deadline - time.time()))
    bags = glob.glob(os.path.join(work, name + "_*.bag"))
    if recorder.returncode != 0 or len(bags) != 1:
        sys.exit("record_sample_bags: %s: record.launch exited %s, bags %s (log %s)" % (
            name, recorder.returncode, bags, os.path.join(work, name + ".log")))
    target = os.path.join(out_dir, name + ".bag")
    shutil.move(bags[0], target)
    size_mb = os.path.getsize(target) / 1e6
    print("record_sample_bags: %s %.1f MB" % (target, size_mb), flush=True)
    if size_mb > max_mb:
        sys.exit("record_sample_bags: %s is %.1f MB, over %.0f MB: fewer --seconds or a lower --camera-rate-hz"
                 % (target, size_mb, max_mb))
    return size_mb


def main():
    args = parse_args()
    work = tempfile.mkdtemp(prefix="sample_bags_")
    port = launch_runner.free_port()
    env = dict(os.environ, ROS_MASTER_URI="http://127.0.0.1:%d" % port)
    os.environ["ROS_MASTER_URI"] = env["ROS_MASTER_URI"]
    deadline = time.time() + args.timeout_s
    sim_log = open(os.path.join(work, "sim.log"), "w")
    sim = subprocess.Popen(["roslaunch", "-p", str(port), os.path.join(LAUNCH, "sim.launch"),
                            "scenario:=" + args.scenario, "dock:=false", "output:=log",
                            "stereo_right_rate_hz:=0",  # every stereo pair: the far bag is the disparity detector's
                            "camera_rate_hz:=%g" % args.camera_rate_hz,
                            "real_time_factor:=%g" % args.real_time_factor],
                           env=env, stdout=sim_log, stderr=subprocess.STDOUT, start_new_session=True)
    try:
        wait_for_cameras(env, 240.0)
        far = start_recording(env, os.path.join(work, "far_approach"), args.seconds, work, "far_approach")
        wait_until_recording(env, deadline)
        dock = subprocess.Popen(["rosrun", "docking_planner", "dock", "start"], env=env,
                                stdout=open(os.path.join(work, "dock.log"), "w"), stderr=subprocess.STDOUT)
        import rospy
        rospy.init_node("record_sample_bags", anonymous=True, disable_signals=True)
        if not wait_for_port_within(args.near_range_m, deadline):
            sys.exit("record_sample_bags: the chaser never came within %.2f m (log %s)" % (
                args.near_range_m, sim_log.name))
        near = start_recording(env, os.path.join(work, "near_approach"), args.seconds, work, "near_approach")
        os.makedirs(args.out_dir, exist_ok=True)
        sizes = [finish(far, "far_approach", work, args.out_dir, args.max_mb, deadline),
                 finish(near, "near_approach", work, args.out_dir, args.max_mb, deadline)]
        print("record_sample_bags: done, %.1f MB in all (work folder %s)" % (sum(sizes), work), flush=True)
        dock.wait(timeout=max(1.0, deadline - time.time()))
    finally:
        launch_runner.stop(sim)


if __name__ == "__main__":
    main()
