#!/usr/bin/env python3
"""Issue 13: each sample bag of bags/ replayed through replay.launch (lossless, as recorded: compressed
images), its estimates checked against the simulator's truth that the bag holds.

Parameters (the test file sets them per bag):
  ~bag     the bag, relative to the repository (bags/far_approach.bag)
  ~checks  [[estimate topic, truth topic, min valid rate, max median position error m,
              max p95 position error m, max median orientation error deg (negative: not checked)], ...]
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
    def test_replay_against_truth(self):
        rospy.init_node("sample_bags_check")
        repo = os.path.abspath(os.path.join(rospkg.RosPack().get_path(PKG), "..", ".."))
        bag = os.path.join(repo, rospy.get_param("~bag"))
        self.assertTrue(os.path.isfile(bag), "no sample bag %s" % bag)
        self.assertLessEqual(os.path.getsize(bag), 20e6, "%s is over 20 MB" % bag)
        work = tempfile.mkdtemp(prefix="sample_bags_")
        try:
            out = self.replay(repo, bag, work)
            for topic, truth_topic, min_rate, max_median_m, max_p95_m, max_rot_deg in rospy.get_param("~checks"):
                self.check(bag, out, topic, truth_topic, min_rate, max_median_m, max_p95_m, max_rot_deg)
        finally:
            shutil.rmtree(work, ignore_errors=True)

    def replay(self, repo, bag, work):
        """replay.launch lossless:=true on a master of its own; returns the bag of what it made."""
        port = free_port()
        out = os.path.join(work, "replay.bag")
        log_path = os.path.join(work, "replay.log")
        env = dict(os.environ, ROS_MASTER_URI="http://127.0.0.1:%d" % port)
        with open(log_path, "w") as log:
            rc = subprocess.call(["roslaunch", "-p", str(port), os.path.join(repo, "launch", "replay.launch"),
                                  "bag:=" + bag, "out:=" + out, "lossless:=true", "dock:=false"],
                                 env=env, stdout=log, stderr=subprocess.STDOUT, timeout=900)
        if rc != 0:
            kept = os.path.join(tempfile.gettempdir(), "sample_bags_failed_replay.log")
            shutil.copy(log_path, kept)
            problems = [line for line in open(log_path) if any(w in line for w in ("died", "ERROR", "FATAL", "rror"))]
            self.fail("replay.launch exited %s (log kept in %s): %s" % (rc, kept, "".join(problems[-15:])))
        return out

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


if __name__ == "__main__":
    rostest.rosrun(PKG, "sample_bags", SampleBag, sys.argv)
