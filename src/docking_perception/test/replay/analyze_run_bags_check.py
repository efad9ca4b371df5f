#!/usr/bin/env python3
"""Issue 13: scripts/demo/analyze_run.py reads the bags of both recorders and older ones with relative
topic names. Small bags are written here with the topics each recorder stores (launch/sim.launch bag:=
with the simulator's truth; launch/record.launch with images and no truth) at known poses, so the
figures are known: a simulator bag gives the docking and perception errors against the truth, a robot
bag the states and detection rates and names what it lacks, and a relative-name copy of either gives
the same summary. A bag with none of the topics is refused with a message. No simulator: seconds."""
import math
import pathlib
import shutil
import sys
import tempfile
import unittest

import rosbag
import rospy
import rostest
from docking_msgs.msg import DockingState, TargetEstimate
from geometry_msgs.msg import TransformStamped
from nav_msgs.msg import Odometry
from sensor_msgs.msg import Image
from std_msgs.msg import String
from tf2_msgs.msg import TFMessage

PKG = "docking_perception"
ROOT = pathlib.Path(__file__).resolve().parents[4]  # the repository this test belongs to
sys.path.insert(0, str(ROOT / "scripts" / "demo"))
import analyze_run  # noqa: E402

PROBE_X = 0.18
FRAMES = 20                # at 10 Hz from t = 1 s
TIP_OFFSET_M = 0.004       # the probe tip stops 4 mm short of the port
ESTIMATE_ERROR_M = 0.01    # the disparity estimate is 1 cm off the truth
DETECTED = 15              # of FRAMES disparity estimates valid


def stamp(i):
    return rospy.Time.from_sec(1.0 + 0.1 * i)


def transform(parent, child, t, x, y, yaw):
    tr = TransformStamped()
    tr.header.stamp, tr.header.frame_id, tr.child_frame_id = t, parent, child
    tr.transform.translation.x, tr.transform.translation.y = x, y
    tr.transform.rotation.z, tr.transform.rotation.w = math.sin(yaw / 2), math.cos(yaw / 2)
    return tr


def messages(with_truth, with_images):
    """(topic, message, time) of one run: the chaser still in front of the port, docked at the end."""
    port_x = PROBE_X + TIP_OFFSET_M
    for i in range(FRAMES):
        t = stamp(i)
        frames = [transform("odom", "base_link", t, 0.0, 0.0, 0.0)]
        if with_truth:
            frames += [transform("world", "chaser_truth", t, 0.0, 0.0, 0.0),
                       transform("world", "target_truth", t, port_x, 0.0, math.pi)]
        yield "/tf", TFMessage(transforms=frames), t
        state = DockingState(state=DockingState.DOCKED if i == FRAMES - 1 else DockingState.FINAL,
                             target_visible=True, estimate_source=0, range_m=port_x)
        state.header.stamp = t
        state.state_name = "DOCKED" if i == FRAMES - 1 else "FINAL"
        state.reason = "test"
        yield "/docking/state", state, t
        estimate = TargetEstimate(valid=i < DETECTED, position_valid=i < DETECTED, range_m=0.5)
        estimate.header.stamp, estimate.header.frame_id = t, "stereo_left_optical_frame"
        estimate.pose.pose.position.z = 0.5 + ESTIMATE_ERROR_M
        yield "/perception/disparity/estimate", estimate, t
        if with_truth:
            truth = Odometry()
            truth.header.stamp, truth.header.frame_id = t, "stereo_left_optical_frame"
            truth.pose.pose.position.z = 0.5
            truth.pose.pose.orientation.w = 1.0
            yield "/sim/truth/stereo_left", truth, t
            yield "/target/arbiter_status", String(data="disparity"), t
        if with_images:
            image = Image(height=2, width=2, encoding="mono8", step=2, data=bytes(4))
            image.header.stamp = t
            yield "/stereo/left/image_raw", image, t


def write_bag(path, items, relative=False):
    with rosbag.Bag(str(path), "w") as bag:
        for topic, msg, t in items:
            bag.write(topic.lstrip("/") if relative else topic, msg, t)
    return path


class AnalyzeRunBags(unittest.TestCase):
    @classmethod
    def setUpClass(cls):
        cls.dir = pathlib.Path(tempfile.mkdtemp(prefix="analyze_run_bags_"))

    @classmethod
    def tearDownClass(cls):
        shutil.rmtree(cls.dir, ignore_errors=True)

    def analyze(self, name, relative, with_truth, with_images):
        bag = write_bag(self.dir / (name + ".bag"), messages(with_truth, with_images), relative)
        summary, data, raw = analyze_run.analyze(bag, probe_x=PROBE_X)
        out = self.dir / name
        out.mkdir()
        analyze_run.plot(summary, data, raw, out)
        analyze_run.print_summary(summary)
        return summary, out

    def test_simulator_bag(self):
        for relative in (False, True):
            summary, out = self.analyze("sim_relative" if relative else "sim", relative, True, False)
            self.assertTrue(summary["truth"])
            self.assertTrue(summary["docked"])
            self.assertAlmostEqual(summary["final_position_error_m"], TIP_OFFSET_M, places=9)
            self.assertAlmostEqual(summary["final_yaw_error_deg"], 0.0, places=6)
            disparity = summary["perception"]["disparity"]
            self.assertAlmostEqual(disparity["position_error_median_m"], ESTIMATE_ERROR_M, places=9)
            self.assertAlmostEqual(disparity["detection_rate"], DETECTED / FRAMES)
            self.assertTrue((out / "trajectory.png").exists() and (out / "timeline.png").exists())

    def test_robot_bag(self):
        for relative in (False, True):
            summary, out = self.analyze("robot_relative" if relative else "robot", relative, False, True)
            self.assertFalse(summary["truth"])
            self.assertIsNone(summary["final_position_error_m"])
            self.assertTrue(summary["docked"])
            self.assertEqual(summary["states_visited"], ["FINAL", "DOCKED"])
            disparity = summary["perception"]["disparity"]
            self.assertAlmostEqual(disparity["detection_rate"], DETECTED / FRAMES)
            self.assertIsNone(disparity["position_error_median_m"])
            missing = "\n".join(summary["missing"])
            for topic in ("/sim/truth/stereo_left", "/target/arbiter_status", "world -> *_truth"):
                self.assertIn(topic, missing)
            self.assertNotIn("/docking/state", missing)
            self.assertFalse((out / "trajectory.png").exists(), "a trajectory drawn without truth")
            self.assertTrue((out / "timeline.png").exists())

    def test_relative_names_give_the_same_summary(self):
        absolute, _ = self.analyze("abs_same", False, True, True)
        relative, _ = self.analyze("rel_same", True, True, True)
        absolute.pop("bag")
        relative.pop("bag")
        self.assertEqual(absolute, relative)

    def test_bag_without_any_topic_it_reads(self):
        images = [(topic, msg, t) for topic, msg, t in messages(False, True) if "image" in topic]
        bag = write_bag(self.dir / "images.bag", images)
        with self.assertRaisesRegex(RuntimeError, "none of the topics"):
            analyze_run.analyze(bag, probe_x=PROBE_X)


if __name__ == "__main__":
    rostest.rosrun(PKG, "analyze_run_bags_check", AnalyzeRunBags)
