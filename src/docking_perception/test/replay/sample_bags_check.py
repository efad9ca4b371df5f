#!/usr/bin/env python3
"""Issue 13: each sample bag of bags/ replayed through replay.launch (lossless, as recorded: compressed
images), its estimates checked against the simulator's truth that the bag holds.

Parameters (the test file sets them):
  ~bags    {name: {bag: the bag, relative to the repository (bags/far_approach.bag),
                   checks: [[estimate topic, truth topic, min valid rate, max median position error m,
                             max p95 position error m, max median orientation error deg (negative: not
                             checked)], ...]}, ...}
The bags replay side by side (each replay.launch on a master of its own), then each is checked in a
test of its own (test_<name>).
For every check: the share of the bag's frames with a valid estimate is at least the minimum, and the
position error (estimate minus truth at the same stamp, both in the camera's optical frame) has a median
and a p95 within the limits; where the orientation is checked, its median error too. The figures are
printed (bags/README.md quotes them).
"""
import math
import os
import shutil
import subprocess
import sys
import tempfile
import unittest

import rosbag
import rospkg
import rospy
import rostest

PKG = "docking_perception"
# One free_port for every script that starts a master of its own (scripts/tune/launch_runner.py).
sys.path.insert(0, os.path.join(rospkg.RosPack().get_path(PKG), "..", "..", "scripts", "tune"))
from launch_runner import free_port  # noqa: E402



def quantile(values, q):
    ordered = sorted(values)
    return ordered[min(len(ordered) - 1, int(q * len(ordered)))]


def rotation_angle_deg(a, b):
    """The angle of the rotation between two unit quaternions (geometry_msgs/Quaternion)."""
    dot = abs(a.x * b.x + a.y * b.y + a.z * b.z + a.w * b.w)
    return math.degrees(2.0 * math.acos(min(1.0, dot)))


def by_stamp(bag_path, topic):
    with rosbag.Bag(bag_path) as bag:
        return {msg.header.stamp.to_nsec(): msg for _, msg, _ in bag.read_messages(topics=[topic])}


class SampleBag(unittest.TestCase):
    """One test per sample bag (test_<name>, added from ~bags); the replays run once, side by side."""
    repo = os.path.abspath(os.path.join(rospkg.RosPack().get_path(PKG), "..", ".."))
    ports = []   # the masters' ports, each its own
    outs = {}    # name -> the bag of what its replay made, or the reason it failed
    work = None

    @classmethod
    def setUpClass(cls):
        cls.work = tempfile.mkdtemp(prefix="sample_bags_")
        bags = rospy.get_param("~bags")
        procs = {}
        try:
            for name, entry in sorted(bags.items()):
                bag = os.path.join(cls.repo, entry["bag"])
                if not os.path.isfile(bag) or os.path.getsize(bag) > 20e6:
                    continue  # said by its test
                procs[name] = cls.start_replay(bag, os.path.join(cls.work, name))
            for name, (proc, out, log_path) in procs.items():
                rc = proc.wait(timeout=900)
                cls.outs[name] = out if rc == 0 else cls.failed_replay(name, rc, log_path)
        finally:
            for proc, _, _ in procs.values():
                if proc.poll() is None:
                    os.killpg(proc.pid, 2)
                    proc.wait(timeout=30)

    @classmethod
    def tearDownClass(cls):
        shutil.rmtree(cls.work, ignore_errors=True)

    def check_bag(self, name):
        entry = rospy.get_param("~bags")[name]
        bag = os.path.join(self.repo, entry["bag"])
        self.assertTrue(os.path.isfile(bag), "no sample bag %s" % bag)
        self.assertLessEqual(os.path.getsize(bag), 20e6, "%s is over 20 MB" % bag)
        out = self.outs.get(name, "no replay")
        self.assertTrue(os.path.isfile(out), out)
        for topic, truth_topic, min_rate, max_median_m, max_p95_m, max_rot_deg in entry["checks"]:
            self.check(bag, out, topic, truth_topic, min_rate, max_median_m, max_p95_m, max_rot_deg)

    @staticmethod
    def start_replay(bag, work):
        """replay.launch lossless:=true on a master of its own; returns (process, its output bag, its log)."""
        os.makedirs(work)
        port = free_port()
        while port in SampleBag.ports:
            port = free_port()
        SampleBag.ports.append(port)
        out = os.path.join(work, "replay.bag")
        log_path = os.path.join(work, "replay.log")
        env = dict(os.environ, ROS_MASTER_URI="http://127.0.0.1:%d" % port)
        with open(log_path, "w") as log:
            proc = subprocess.Popen(["roslaunch", "-p", str(port), os.path.join(SampleBag.repo, "launch", "replay.launch"),
                                     "bag:=" + bag, "out:=" + out, "lossless:=true", "dock:=false"],
                                    env=env, stdout=log, stderr=subprocess.STDOUT, start_new_session=True)
        return proc, out, log_path

    @staticmethod
    def failed_replay(name, rc, log_path):
        kept = os.path.join(tempfile.gettempdir(), "sample_bags_failed_replay_%s.log" % name)
        shutil.copy(log_path, kept)
        problems = [line for line in open(log_path) if any(w in line for w in ("died", "ERROR", "FATAL", "rror"))]
        return "replay.launch exited %s (log kept in %s): %s" % (rc, kept, "".join(problems[-15:]))

    def check(self, bag, out, topic, truth_topic, min_rate, max_median_m, max_p95_m, max_rot_deg):
        truth = by_stamp(bag, truth_topic)
        replayed = by_stamp(out, topic)
        valid = {s: m for s, m in replayed.items() if m.valid and m.position_valid and s in truth}
        rate = len(valid) / float(len(truth))  # the truth has one message per camera frame
        errors = []
        rotations = []
        for stamp, estimate in valid.items():
            reference = truth[stamp]
            self.assertEqual(estimate.header.frame_id, reference.header.frame_id, topic)
            p, q = estimate.pose.pose.position, reference.pose.pose.position
            errors.append(math.sqrt((p.x - q.x) ** 2 + (p.y - q.y) ** 2 + (p.z - q.z) ** 2))
            if estimate.orientation_valid:
                rotations.append(rotation_angle_deg(estimate.pose.pose.orientation, reference.pose.pose.orientation))
        name = "%s %s" % (os.path.basename(bag), topic)
        self.assertGreater(len(errors), 0, "%s: no valid estimate at a truth stamp" % name)
        median, p95 = quantile(errors, 0.5), quantile(errors, 0.95)
        rot_median = quantile(rotations, 0.5) if rotations else float("nan")
        print("sample_bags_check: %s: valid %d/%d frames (%.2f), position error median %.1f mm, p95 %.1f mm, "
              "orientation error median %.2f deg over %d" % (name, len(valid), len(truth), rate, 1e3 * median,
                                                              1e3 * p95, rot_median, len(rotations)), flush=True)
        self.assertGreaterEqual(rate, min_rate, "%s: valid rate" % name)
        self.assertLessEqual(median, max_median_m, "%s: median position error" % name)
        self.assertLessEqual(p95, max_p95_m, "%s: p95 position error" % name)
        if max_rot_deg >= 0:
            self.assertTrue(rotations, "%s: no orientation" % name)
            self.assertLessEqual(rot_median, max_rot_deg, "%s: median orientation error" % name)


def add_tests():
    for name in sorted(rospy.get_param("~bags")):
        setattr(SampleBag, "test_" + name, lambda self, name=name: self.check_bag(name))


if __name__ == "__main__":
    rospy.init_node("sample_bags_check")
    add_tests()
    rostest.rosrun(PKG, "sample_bags", SampleBag, sys.argv)
