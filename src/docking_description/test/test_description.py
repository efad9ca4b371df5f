#!/usr/bin/env python3
"""launch/description.launch against the YAML it is generated from: what robot_state_publisher puts on
tf, the URDFs' structure, and the generator's errors for a broken robot.yaml / omni_base.yaml."""
import math
import os
import shutil
import subprocess
import sys
import tempfile
import unittest
import xml.etree.ElementTree as ET

import rospy
import rostest
import tf2_ros
import yaml
from sensor_msgs.msg import JointState

TOL = 1e-6
SCRIPT = os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "scripts", "make_urdf.py")


def quaternion_from_fixed_rpy(roll, pitch, yaw):
    """(x, y, z, w) of Rz(yaw) Ry(pitch) Rx(roll): URDF's and robot.yaml's convention."""
    cr, sr = math.cos(roll / 2), math.sin(roll / 2)
    cp, sp = math.cos(pitch / 2), math.sin(pitch / 2)
    cy, sy = math.cos(yaw / 2), math.sin(yaw / 2)
    return (sr * cp * cy - cr * sp * sy,
            cr * sp * cy + sr * cp * sy,
            cr * cp * sy - sr * sp * cy,
            cr * cp * cy + sr * sp * sy)


def rotate(q, v):
    """Rotates vector v by the unit quaternion q = (x, y, z, w)."""
    x, y, z, w = q
    # v' = v + 2 w (u x v) + 2 u x (u x v), u = (x, y, z)
    ux = (y * v[2] - z * v[1], z * v[0] - x * v[2], x * v[1] - y * v[0])
    uux = (y * ux[2] - z * ux[1], z * ux[0] - x * ux[2], x * ux[1] - y * ux[0])
    return tuple(v[i] + 2 * w * ux[i] + 2 * uux[i] for i in range(3))


class Description(unittest.TestCase):
    @classmethod
    def setUpClass(cls):
        rospy.init_node("test_description")
        cls.config_dir = rospy.get_param("~config_dir")
        with open(os.path.join(cls.config_dir, "robot.yaml")) as f:
            cls.robot = yaml.safe_load(f)["chaser"]
        with open(os.path.join(cls.config_dir, "omni_base.yaml")) as f:
            cls.wheels = yaml.safe_load(f)["wheels"]
        with open(os.path.join(cls.config_dir, "target.yaml")) as f:
            cls.target = yaml.safe_load(f)["target"]
        cls.buffer = tf2_ros.Buffer()
        cls.listener = tf2_ros.TransformListener(cls.buffer)
        cls.joint_pub = rospy.Publisher("/joint_states", JointState, queue_size=10)

    def lookup(self, parent, child, timeout=30.0):
        return self.buffer.lookup_transform(parent, child, rospy.Time(0), rospy.Duration(timeout)).transform

    def assertVectorNear(self, actual, expected, what):
        for i in range(3):
            self.assertAlmostEqual(actual[i], expected[i], delta=TOL, msg="%s[%d]: %r vs %r" % (what, i, actual, expected))

    def assertQuaternionNear(self, actual, expected, what):
        # q and -q are the same rotation
        sign = 1.0 if sum(a * e for a, e in zip(actual, expected)) >= 0 else -1.0
        for i in range(4):
            self.assertAlmostEqual(actual[i], sign * expected[i], delta=TOL,
                                   msg="%s: %r vs %r" % (what, actual, expected))

    def test_camera_frames_equal_robot_yaml(self):
        base = self.robot["base_frame"]
        self.assertEqual(len(self.robot["cameras"]), 3)
        for key, cam in self.robot["cameras"].items():
            t = self.lookup(base, cam["frame_id"])
            self.assertVectorNear((t.translation.x, t.translation.y, t.translation.z), cam["xyz_m"], key + " xyz")
            self.assertQuaternionNear((t.rotation.x, t.rotation.y, t.rotation.z, t.rotation.w),
                                      quaternion_from_fixed_rpy(*cam["rpy_rad"]), key + " rotation")
            # REP 103 optical frame: for these mounts the lens axis (z) looks along base_link +x.
            z_axis = rotate((t.rotation.x, t.rotation.y, t.rotation.z, t.rotation.w), (0, 0, 1))
            self.assertVectorNear(z_axis, (1, 0, 0), key + " optical axis")

    def test_probe_tip(self):
        t = self.lookup(self.robot["base_frame"], "docking_probe")
        self.assertVectorNear((t.translation.x, t.translation.y, t.translation.z),
                              (self.robot["docking_probe_x_m"], 0.0, self.target["mount"]["xyz_m"][2]), "probe")

    def test_wheels_at_their_drive_angles_and_turning_about_their_axles(self):
        names = self.wheels["names"]
        L, r = self.wheels["center_distance_m"], self.wheels["radius_m"]
        angles = [0.0, math.pi / 2, -1.0]
        msg = JointState(name=names, position=angles, velocity=[0.0] * len(names))
        deadline = rospy.Time.now() + rospy.Duration(30.0)
        found = {}
        while rospy.Time.now() < deadline and len(found) < len(names):
            msg.header.stamp = rospy.Time.now()
            self.joint_pub.publish(msg)
            rospy.sleep(0.1)
            for name in names:
                try:
                    found[name] = self.buffer.lookup_transform(self.robot["base_frame"], name + "_link", rospy.Time(0)).transform
                except tf2_ros.TransformException:
                    pass
        self.assertEqual(sorted(found), sorted(names), "robot_state_publisher did not publish every wheel")
        for name, a_deg, q in zip(names, self.wheels["drive_angles_deg"], angles):
            t = found[name]
            a = math.radians(a_deg)
            p = (t.translation.x, t.translation.y, t.translation.z)
            self.assertAlmostEqual(math.hypot(p[0], p[1]), L, delta=TOL, msg=name + " distance from the centre")
            self.assertAlmostEqual(p[2], r, delta=TOL, msg=name + " axle height")
            drive = (math.cos(a), math.sin(a))
            # omni_base's kinematics: qdot = (cos a vx + sin a vy + L wz) / r, so a pure rotation wz moves
            # this wheel's contact point (wz z x p) along its drive direction at L wz.
            self.assertAlmostEqual(-p[1] * drive[0] + p[0] * drive[1], L, delta=TOL, msg=name + " position")
            rot = (t.rotation.x, t.rotation.y, t.rotation.z, t.rotation.w)
            # The axle: z x drive, horizontal; the joint angle q turns the wheel's x about it.
            self.assertVectorNear(rotate(rot, (0, 1, 0)), (-drive[1], drive[0], 0.0), name + " axle")
            self.assertVectorNear(rotate(rot, (1, 0, 0)),
                                  (drive[0] * math.cos(q), drive[1] * math.cos(q), -math.sin(q)), name + " angle")

    def test_target_model_below_target_frame(self):
        frame = self.target["frame_id"]
        for link in ("target_face_plate", "target_body", "target_solar_panel_pos_y", "target_solar_panel_neg_y"):
            self.lookup(frame, link)  # raises when missing
        panel = self.lookup(frame, "target_solar_panel_pos_y")
        face_w, span = self.target["face"]["width_m"], self.target["solar_panels"]["span_m"]
        self.assertVectorNear((panel.translation.x, panel.translation.y, panel.translation.z),
                              (self.target["solar_panels"]["offset_x_m"], face_w / 2 + span / 2, 0.0), "panel")
        # The target robot's base: the port is at mount (xyz, yaw) in it, so the base is there inverted.
        base = self.lookup(frame, "target_base_link")
        mx, my, mz = self.target["mount"]["xyz_m"]
        yaw = self.target["mount"]["yaw_rad"]
        base_q = (base.rotation.x, base.rotation.y, base.rotation.z, base.rotation.w)
        self.assertQuaternionNear(base_q, quaternion_from_fixed_rpy(0, 0, -yaw), "target base rotation")
        port_in_base = rotate(quaternion_from_fixed_rpy(0, 0, yaw), (-base.translation.x, -base.translation.y,
                                                                      -base.translation.z))
        self.assertVectorNear(port_in_base, (mx, my, mz), "port in the target base")

    def check_urdf(self, text, root, continuous):
        robot = ET.fromstring(text)
        self.assertEqual(robot.tag, "robot")
        links = [l.get("name") for l in robot.findall("link")]
        self.assertEqual(len(links), len(set(links)), "duplicate link names")
        children = []
        for joint in robot.findall("joint"):
            parent, child = joint.find("parent").get("link"), joint.find("child").get("link")
            self.assertIn(parent, links)
            self.assertIn(child, links)
            children.append(child)
            for attr in ("xyz", "rpy"):
                self.assertTrue(all(math.isfinite(float(v)) for v in joint.find("origin").get(attr).split()))
        self.assertEqual(len(children), len(set(children)), "a link with two parents")
        self.assertEqual([l for l in links if l not in children], [root], "the tree's root")
        self.assertEqual(sorted(j.get("name") for j in robot.findall("joint") if j.get("type") == "continuous"),
                         sorted(continuous))
        return robot

    def test_urdfs_are_trees_rooted_where_expected(self):
        chaser = self.check_urdf(rospy.get_param("/robot_description"), self.robot["base_frame"], self.wheels["names"])
        self.assertEqual(len(chaser.findall("link")), 1 + 3 + 1 + 3)  # base, wheels, probe, cameras
        self.check_urdf(rospy.get_param("/target_description"), self.target["frame_id"], [])

    def test_truth_ghost_is_the_target_renamed(self):
        """The simulator's ghost (description.launch truth_ghost:=true): the target model rooted at
        target_truth, every other link prefixed truth_, and each part where the model has it."""
        target = ET.fromstring(rospy.get_param("/target_description"))
        ghost = self.check_urdf(rospy.get_param("/target_truth_description"), "target_truth", [])
        root = self.target["frame_id"]
        links = [l.get("name") for l in target.findall("link") if l.get("name") != root]
        self.assertEqual(sorted(l.get("name") for l in ghost.findall("link")),
                         sorted(["target_truth"] + ["truth_" + name for name in links]))
        for name in links:
            model = self.lookup(root, name)
            copy = self.lookup("target_truth", "truth_" + name)
            self.assertVectorNear((copy.translation.x, copy.translation.y, copy.translation.z),
                                  (model.translation.x, model.translation.y, model.translation.z), name)
            self.assertQuaternionNear((copy.rotation.x, copy.rotation.y, copy.rotation.z, copy.rotation.w),
                                      (model.rotation.x, model.rotation.y, model.rotation.z, model.rotation.w), name)

    def test_generator_refuses_a_root_rename_without_prefix(self):
        run = subprocess.run([sys.executable, SCRIPT, "target", "--config-dir", self.config_dir, "--root-frame",
                              "target_truth"], capture_output=True, text=True, timeout=30)
        self.assertEqual(run.returncode, 2)
        self.assertIn("--root-frame needs --link-prefix", run.stderr)

    # ----- the generator's errors -----
    def generate(self, robot_edit=None, base_edit=None):
        tmp = tempfile.mkdtemp(prefix="make_urdf_test_")
        try:
            for name, edit in (("robot.yaml", robot_edit), ("omni_base.yaml", base_edit), ("target.yaml", None)):
                with open(os.path.join(self.config_dir, name)) as f:
                    data = yaml.safe_load(f)
                if edit:
                    edit(data)
                with open(os.path.join(tmp, name), "w") as f:
                    yaml.safe_dump(data, f, sort_keys=False)  # keep the cameras in their order
            run = subprocess.run([sys.executable, SCRIPT, "chaser", "--config-dir", tmp], capture_output=True,
                                 text=True, timeout=30)
            return run, tmp
        finally:
            shutil.rmtree(tmp)

    def test_generator_output_matches_the_launched_description(self):
        run, _ = self.generate()
        self.assertEqual(run.returncode, 0, run.stderr)
        self.assertEqual(ET.tostring(ET.fromstring(run.stdout)),
                         ET.tostring(ET.fromstring(rospy.get_param("/robot_description"))))

    def test_generator_names_a_missing_camera_key(self):
        run, tmp = self.generate(robot_edit=lambda d: d["chaser"]["cameras"]["ir"].pop("rpy_rad"))
        self.assertEqual(run.returncode, 2)
        self.assertEqual(run.stdout, "")
        self.assertIn(os.path.join(tmp, "robot.yaml") + ": chaser.cameras.ir.rpy_rad: missing", run.stderr)

    def test_generator_names_a_missing_footprint(self):
        run, _ = self.generate(robot_edit=lambda d: d["chaser"].pop("footprint_radius_m"))
        self.assertEqual(run.returncode, 2)
        self.assertIn("chaser.footprint_radius_m: missing", run.stderr)

    def test_generator_rejects_a_bad_wheel_layout(self):
        run, tmp = self.generate(base_edit=lambda d: d["wheels"]["drive_angles_deg"].pop())
        self.assertEqual(run.returncode, 2)
        self.assertIn(os.path.join(tmp, "omni_base.yaml") + ": wheels.drive_angles_deg: has 2 angles for 3 wheels",
                      run.stderr)
        run, _ = self.generate(base_edit=lambda d: d["wheels"].update(radius_m="big"))
        self.assertEqual(run.returncode, 2)
        self.assertIn("wheels.radius_m: expected a finite number", run.stderr)


if __name__ == "__main__":
    rostest.rosrun("docking_description", "description", Description)
