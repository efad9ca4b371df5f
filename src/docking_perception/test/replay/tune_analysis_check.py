#!/usr/bin/env python3
"""Issue 13: the tuning tool's analysis, YAML edit and launch-output reading (scripts/tune), without a
replay (seconds).

The test writes, with the rosbag API, an input bag (camera frames, the simulator's truth, the static
camera frames) and two output bags (configurations A and B) whose estimates are the truth plus known
offsets, and checks that tune_analysis finds exactly those: detection rates, errors against the truth
(including the fused estimates at stamps where only the IR camera has a truth, which must be carried
into the stereo frame through /tf_static), per-stamp differences and validity flips between A and B,
and the CPU statistics. Then the YAML line edit: one line changed, every comment kept at its column,
nested keys by dots, and an unknown key or a mapping refused with the file left as it was. Last, the
replay runner's reading of roslaunch's output: a node's refusal found and quoted, the normal end not.
"""
import math
import os
import shutil
import sys
import tempfile
import unittest

import numpy as np
import rosbag
import rospkg
import rospy
import rostest
from docking_msgs.msg import TargetEstimate
from geometry_msgs.msg import TransformStamped
from nav_msgs.msg import Odometry
from sensor_msgs.msg import CameraInfo
from tf2_msgs.msg import TFMessage

PKG = "docking_perception"
sys.path.insert(0, os.path.join(rospkg.RosPack().get_path(PKG), "..", "..", "scripts", "tune"))
import launch_runner  # noqa: E402
import tune_analysis  # noqa: E402
import tune_replay  # noqa: E402
import tune_report  # noqa: E402
from tune_analysis import Pose  # noqa: E402
from yaml_line_edit import KeyEditError, set_key  # noqa: E402

FRAMES = 10
STAMPS = [rospy.Time(1.0 + 0.1 * i) for i in range(FRAMES)]
STEREO, IR = "stereo_left_optical_frame", "ir_optical_frame"
NO_STEREO_TRUTH = (3, 6)  # frames whose stereo truth is left out: the fused estimate needs the IR one


def quaternion_about(axis, angle_deg):
    axis = np.asarray(axis, dtype=float) / np.linalg.norm(axis)
    half = math.radians(angle_deg) / 2.0
    return np.append(axis * math.sin(half), math.cos(half))


# The mounts (base_link -> optical frames): the IR camera 5 cm above, 5 cm right of the left one and
# turned 4 deg about its own x, so that a wrong frame change shows in the errors.
OPTICAL = quaternion_about([1.0, -1.0, 1.0], -120.0)  # REP 103 optical frame on a forward-looking mount
LEFT_MOUNT = Pose(np.array([0.10, 0.05, 0.25]), OPTICAL)
IR_MOUNT = Pose(np.array([0.10, 0.0, 0.30]), tune_analysis.quaternion_multiply(OPTICAL, quaternion_about([1, 0, 0], 4.0)))


def port_in_left(i):
    """The truth: the port 2.5 m ahead, drifting right, yawed 20 deg and turning."""
    return Pose(np.array([0.05 * i - 0.2, 0.01, 2.5 - 0.02 * i]), quaternion_about([0.2, 1.0, 0.1], 20.0 + i))


def port_in_ir(i):
    return IR_MOUNT.inverse().compose(LEFT_MOUNT).compose(port_in_left(i))


def offset(pose, d_position=(0, 0, 0), rotation_deg=0.0):
    """A pose moved by d_position (m, in the camera frame) and turned rotation_deg about the camera's x."""
    return Pose(pose.position + np.asarray(d_position, dtype=float),
                tune_analysis.quaternion_multiply(quaternion_about([1, 0, 0], rotation_deg), pose.quaternion))


def set_pose(msg_pose, pose):
    msg_pose.position.x, msg_pose.position.y, msg_pose.position.z = pose.position
    q = msg_pose.orientation
    q.x, q.y, q.z, q.w = pose.quaternion


def estimate(stamp, frame, source, pose=None, orientation=False, range_m=None, cpu_ms=1.0):
    msg = TargetEstimate()
    msg.header.stamp, msg.header.frame_id = stamp, frame
    msg.source = msg.selected_source = source
    msg.processing_time_ms = cpu_ms
    if pose is not None:
        msg.valid = msg.position_valid = True
        msg.orientation_valid = orientation
        set_pose(msg.pose.pose, pose)
        msg.range_m = float(np.linalg.norm(pose.position)) if range_m is None else range_m
    else:
        msg.status = "not found"
    return msg


def static_transform(child, mount):
    transform = TransformStamped()
    transform.header.frame_id, transform.child_frame_id = "base_link", child
    t, q = transform.transform.translation, transform.transform.rotation
    t.x, t.y, t.z = mount.position
    q.x, q.y, q.z, q.w = mount.quaternion
    return transform


def write_input_bag(path):
    with rosbag.Bag(path, "w") as bag:
        bag.write("/tf_static", TFMessage([static_transform(STEREO, LEFT_MOUNT), static_transform(IR, IR_MOUNT)]),
                  STAMPS[0])
        for i, stamp in enumerate(STAMPS):
            for topic, frame in (("/stereo/left/camera_info", STEREO), ("/ir/camera_info", IR)):
                info = CameraInfo()
                info.header.stamp, info.header.frame_id = stamp, frame
                bag.write(topic, info, stamp)
            for topic, frame, pose in (("/sim/truth/stereo_left", STEREO, port_in_left(i)),
                                       ("/sim/truth/ir", IR, port_in_ir(i))):
                if frame == STEREO and i in NO_STEREO_TRUTH:
                    continue
                odometry = Odometry()
                odometry.header.stamp, odometry.header.frame_id, odometry.child_frame_id = stamp, frame, "target"
                set_pose(odometry.pose.pose, pose)
                bag.write(topic, odometry, stamp)


def write_output_bag(path, config_b):
    """A: disparity valid in frames 0-7, 10 mm off in x, range 5 mm long, CPU i+1 ms; mono_visible
    valid but frame 9 unanswered, 2 mm off in z and turned 2 deg; mono_ir exact; fused 3 mm off in y,
    valid everywhere, plus a "nothing valid" re-publication on frame 5's stamp.
    B: disparity also valid in frame 8 and 4 mm further off in y; mono_visible turned 3 deg."""
    with rosbag.Bag(path, "w") as bag:
        for i, stamp in enumerate(STAMPS):
            truth = port_in_left(i)
            if i < (9 if config_b else 8):
                moved = offset(truth, (0.010, 0.004 if config_b else 0.0, 0.0))
                disparity = estimate(stamp, STEREO, 0, moved, range_m=float(np.linalg.norm(truth.position)) + 0.005,
                                     cpu_ms=i + 1.0)
            else:
                disparity = estimate(stamp, STEREO, 0, cpu_ms=i + 1.0)
            bag.write("/perception/disparity/estimate", disparity, stamp)
            if i < 9:
                turned = offset(truth, (0.0, 0.0, 0.002), 3.0 if config_b else 2.0)
                bag.write("/perception/mono_visible/estimate", estimate(stamp, STEREO, 1, turned, True), stamp)
            bag.write("/perception/mono_ir/estimate", estimate(stamp, IR, 2, port_in_ir(i), True), stamp)
            bag.write("/target/estimate", estimate(stamp, STEREO, 3, offset(truth, (0.0, 0.003, 0.0)), True), stamp)
            if i == 5:
                bag.write("/target/estimate", estimate(stamp, STEREO, 3), stamp)


class TuneAnalysis(unittest.TestCase):
    @classmethod
    def setUpClass(cls):
        cls.dir = tempfile.mkdtemp(prefix="tune_analysis_")
        cls.input_bag = os.path.join(cls.dir, "input.bag")
        write_input_bag(cls.input_bag)
        outputs = [os.path.join(cls.dir, "a.bag"), os.path.join(cls.dir, "b.bag")]
        write_output_bag(outputs[0], False)
        write_output_bag(outputs[1], True)
        cls.result = tune_analysis.analyse(cls.input_bag, outputs)
        cls.a, cls.b = cls.result["configurations"]

    @classmethod
    def tearDownClass(cls):
        shutil.rmtree(cls.dir, ignore_errors=True)

    def assertStats(self, stats, median, p95, n, places=6):
        self.assertEqual(stats["n"], n)
        self.assertAlmostEqual(stats["median"], median, places=places)
        self.assertAlmostEqual(stats["p95"], p95, places=places)

    def test_frames_and_detection_rates(self):
        self.assertTrue(self.result["truth"])
        self.assertEqual(self.result["frames"], {"stereo/left": FRAMES, "ir": FRAMES})
        expected = {"disparity": (0.8, 0.9), "mono_visible": (0.9, 0.9), "mono_ir": (1.0, 1.0), "fused": (1.0, 1.0)}
        for source, (rate_a, rate_b) in expected.items():
            self.assertAlmostEqual(self.a[source]["detection_rate"], rate_a, msg=source)
            self.assertAlmostEqual(self.b[source]["detection_rate"], rate_b, msg=source)
        self.assertEqual(self.a["mono_visible"]["answered_frames"], 9)
        self.assertEqual(self.a["fused"]["repeated_stamps"], 1)  # the invalid re-publication did not win

    def test_errors_against_truth(self):
        self.assertStats(self.a["disparity"]["position_error_mm"], 10.0, 10.0, 8)
        self.assertStats(self.a["disparity"]["range_error_mm"], 5.0, 5.0, 8)
        self.assertAlmostEqual(self.a["disparity"]["range_bias_mm"], 5.0, places=6)
        self.assertEqual(self.a["disparity"]["orientation_error_deg"]["n"], 0)  # position only
        self.assertStats(self.b["disparity"]["position_error_mm"], math.hypot(10.0, 4.0), math.hypot(10.0, 4.0), 9)
        self.assertStats(self.a["mono_visible"]["position_error_mm"], 2.0, 2.0, 9)
        self.assertStats(self.a["mono_visible"]["orientation_error_deg"], 2.0, 2.0, 9)
        self.assertStats(self.a["mono_ir"]["position_error_mm"], 0.0, 0.0, FRAMES)
        self.assertStats(self.a["mono_ir"]["orientation_error_deg"], 0.0, 0.0, FRAMES, places=4)
        # Fused, in the stereo frame: frames 3 and 6 have only the IR truth, carried over by /tf_static.
        self.assertEqual(self.a["fused"]["valid_without_truth"], 0)
        self.assertStats(self.a["fused"]["position_error_mm"], 3.0, 3.0, FRAMES)
        self.assertStats(self.a["fused"]["orientation_error_deg"], 0.0, 0.0, FRAMES, places=4)

    def test_differences_between_configurations(self):
        for source in tune_analysis.SOURCES:
            same = self.a[source]["difference_to_reference"]
            self.assertEqual(same["validity_flips"], 0, source)
            if same["position_mm"]["n"]:
                self.assertAlmostEqual(same["position_mm"]["p95"], 0.0, places=9)
        disparity = self.b["disparity"]["difference_to_reference"]
        self.assertStats(disparity["position_mm"], 4.0, 4.0, 8)
        self.assertEqual((disparity["validity_flips"], disparity["valid_only_in_this"],
                          disparity["valid_only_in_reference"]), (1, 1, 0))
        visible = self.b["mono_visible"]["difference_to_reference"]
        self.assertStats(visible["orientation_deg"], 1.0, 1.0, 9)
        self.assertStats(visible["position_mm"], 0.0, 0.0, 9)

    def test_cpu_statistics(self):
        cpu = self.a["disparity"]["cpu_ms"]
        values = np.arange(1.0, FRAMES + 1.0)  # numpy's linear percentiles, as documented
        self.assertStats(cpu, 5.5, float(np.percentile(values, 95)), FRAMES)
        self.assertAlmostEqual(cpu["p95"], 9.55)
        self.assertNotIn("cpu_ms", self.a["fused"])  # the arbiter copies the chosen estimator's

    def test_report_table_and_plot(self):
        report = {"bag": self.input_bag, "truth": True, "camera_frames": self.result["frames"],
                  "configurations": [{"label": "A", "sources": self.a}, {"label": "B", "sources": self.b}]}
        text = tune_report.table(report)
        self.assertIn("80% 8/10", text)
        self.assertIn("4.0 / 4.0", text)
        path = os.path.join(self.dir, "report.png")
        tune_report.plot(report, path)
        with open(path, "rb") as png:
            self.assertEqual(png.read(8), b"\x89PNG\r\n\x1a\n")


YAML_TEXT = """# A commented config.
top: 3          # a comment that explains 3
quoted: "a # not a comment"   # but this is
list_key: [1, 2, 3]  # a list value
chaser:
  base_frame: base_link
  cameras:
    ir:
      xyz_m: [0.10, 0.0, 0.30]   # metres
    stereo_left:
      xyz_m: [0.10, 0.05, 0.25]
"""


class YamlLineEdit(unittest.TestCase):
    def setUp(self):
        self.dir = tempfile.mkdtemp(prefix="tune_yaml_")
        self.path = os.path.join(self.dir, "node.yaml")
        with open(self.path, "w") as stream:
            stream.write(YAML_TEXT)

    def tearDown(self):
        shutil.rmtree(self.dir, ignore_errors=True)

    def lines(self):
        with open(self.path) as stream:
            return stream.read().splitlines()

    def assertOnlyLineChanged(self, index, expected):
        before, after = YAML_TEXT.splitlines(), self.lines()
        self.assertEqual(len(after), len(before))
        for i, (old, new) in enumerate(zip(before, after)):
            self.assertEqual(new, expected if i == index else old, "line %d" % (i + 1))

    def test_scalar_keeps_comment_column(self):
        self.assertEqual(set_key(self.path, "top", "5"), "3")
        self.assertOnlyLineChanged(1, "top: 5          # a comment that explains 3")

    def test_longer_value_and_quoted_hash(self):
        set_key(self.path, "quoted", "plain")
        self.assertOnlyLineChanged(2, 'quoted: plain                 # but this is')
        set_key(self.path, "top", "123456789012345")
        self.assertEqual(self.lines()[1], "top: 123456789012345 # a comment that explains 3")

    def test_nested_key_by_dots(self):
        set_key(self.path, "chaser.cameras.ir.xyz_m", "[0.1, 0.0, 0.35]")
        self.assertOnlyLineChanged(8, "      xyz_m: [0.1, 0.0, 0.35]    # metres")

    def test_unknown_key_refused_file_unchanged(self):
        for key in ("tpo", "chaser.cameras.xyz_m", "xyz_m", "chaser.cameras.ir.xyz_m.x"):
            with self.assertRaises(KeyEditError, msg=key) as caught:
                set_key(self.path, key, "1")
            self.assertIn(key, str(caught.exception))
        self.assertEqual(self.lines(), YAML_TEXT.splitlines())

    def test_mapping_and_bad_value_refused(self):
        with self.assertRaises(KeyEditError):
            set_key(self.path, "chaser.cameras", "1")
        with self.assertRaises(KeyEditError):
            set_key(self.path, "list_key", "[1, 2")
        self.assertEqual(self.lines(), YAML_TEXT.splitlines())

    def test_sweep_values_and_assignments(self):
        self.assertEqual(tune_replay.split_list("1,[2, 3],x"), ["1", "[2, 3]", "x"])
        self.assertEqual(tune_replay.parse_assignment("config/a.yaml:b.c=[1, 2]", "--set"), ("a.yaml", "b.c", "[1, 2]"))
        with self.assertRaises(tune_replay.UsageError):
            tune_replay.parse_assignment("a.yaml:b", "--set")
        with self.assertRaises(tune_replay.UsageError):
            tune_replay.split_list("1,,2")


class LaunchOutput(unittest.TestCase):
    """The replay runner reads roslaunch's output: a refused configuration must stop the replay with
    the node's words, and the normal end (the player, required, exits) must not."""
    REFUSED = [
        "\x1b[31m[FATAL] [1796205318.754374201]: disparity_detector: parameter /disparity_detector/median_kernel_px "
        "must be 0, 1 (off), 3 or 5 (got 4)\x1b[0m",
        "\x1b[31m[disparity_detector-15] process has died [pid 7974, exit code 255, cmd /usr/lib/nodelet/nodelet "
        "load docking_perception/DisparityDetectorNodelet perception_manager].\x1b[0m",
        "\x1b[31m[FATAL] [1796205320.136185174, 1.93]: disparity_detector: parameter /disparity_detector/"
        "median_kernel_px must be 0, 1 (off), 3 or 5 (got 4)\x1b[0m",
        "\x1b[31m[disparity_detector-15] process has died [pid 8151, exit code 255, cmd /usr/lib/nodelet/nodelet].",
    ]
    NORMAL_END = [
        "[INFO] [1796205277.315441, 9.880000]: replay_paced: 240 frames played, 0 skipped (incomplete), "
        "360 estimates waited for, 2 lost (timeout), wall 11.7 s",
        "\x1b[31m[ERROR] [1796205265.66, 1.895]: arbiter: no estimator has published yet (perception stalled or gone)",
        "\x1b[31m================================================================================"
        "REQUIRED process [play-21] has died!",
    ]

    def test_refusal_reported_once_in_the_nodes_words(self):
        self.assertEqual(launch_runner.failure_context(self.REFUSED), [
            "[FATAL] disparity_detector: parameter /disparity_detector/median_kernel_px must be 0, 1 (off), 3 or 5 (got 4)",
            "[disparity_detector-15] process has died [exit code 255"])

    def test_normal_end_is_no_failure(self):
        clean = [launch_runner.ANSI_ESCAPE.sub("", line) for line in self.NORMAL_END]
        self.assertFalse(any(launch_runner.FAILURE.search(line) for line in clean))
        self.assertTrue(all(launch_runner.FAILURE.search(launch_runner.ANSI_ESCAPE.sub("", line))
                            for line in self.REFUSED))
        match = launch_runner.PLAYER_SUMMARY.search(clean[0])
        self.assertEqual((match.group(1), match.group(3)), ("240", "2"))


def all_tests():
    """Both cases in one rostest result (rostest.rosrun runs one case class, or a named suite)."""
    loader = unittest.TestLoader()
    return unittest.TestSuite([loader.loadTestsFromTestCase(case) for case in (TuneAnalysis, YamlLineEdit, LaunchOutput)])


if __name__ == "__main__":
    rostest.rosrun(PKG, "tune_analysis", "__main__.all_tests", sys.argv)
