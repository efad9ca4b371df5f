#!/usr/bin/env python3
"""Prints the URDF of the chaser or of the target, generated from the workspace's YAML.

config/robot.yaml stays the one source of the camera mounts (the simulator and the perception nodes
read it too), so the URDF is generated at launch time instead of being kept as a second copy:

    make_urdf.py chaser --config-dir config    # robot.yaml + omni_base.yaml (+ target.yaml: probe height)
    make_urdf.py target --config-dir config    # target.yaml

--robot, --omni-base and --target override single files. A missing or invalid value stops the script
with exit code 2 and a message naming the file and the key, e.g.
    make_urdf.py: config/robot.yaml: chaser.cameras.ir.xyz_m: missing
"""
import argparse
import math
import os
import sys
import xml.etree.ElementTree as ET

import yaml

# Visual-only sizes that no config file gives (rviz needs some thickness); no frame depends on them.
CHASSIS_THICKNESS_M = 0.03
WHEEL_WIDTH_M = 0.02
CAMERA_BOX_M = (0.03, 0.03, 0.04)  # x, y, z in the optical frame (z forward: the lens axis)
PROBE_ROD_RADIUS_M = 0.008
FACE_PLATE_THICKNESS_M = 0.005
PANEL_THICKNESS_M = 0.005


class ConfigError(Exception):
    pass


class Field:
    """A value in a YAML file with its dotted key, so every error names the file and the key."""

    def __init__(self, path, key, value, present=True):
        self.path, self.key, self.value, self.present = path, key, value, present

    def fail(self, what):
        raise ConfigError("%s: %s: %s" % (self.path, self.key, what))

    def __getitem__(self, name):
        child_key = "%s.%s" % (self.key, name) if self.key else name
        if not self.present:
            return Field(self.path, child_key, None, False)
        if not isinstance(self.value, dict):
            self.fail("expected a map")
        if name not in self.value:
            return Field(self.path, child_key, None, False)
        return Field(self.path, child_key, self.value[name])

    def _require(self):
        if not self.present or self.value is None:
            self.fail("missing")
        return self.value

    def has(self, name):
        return self.present and isinstance(self.value, dict) and name in self.value

    def items(self):
        value = self._require()
        if not isinstance(value, dict) or not value:
            self.fail("expected a non-empty map")
        return [(str(k), self[k]) for k in value]

    def string(self):
        value = self._require()
        if not isinstance(value, str) or not value.strip():
            self.fail("expected a non-empty string")
        if any(c.isspace() for c in value) or "/" in value:
            self.fail("'%s' is not a valid link or joint name (no spaces or slashes)" % value)
        return value

    def number(self, low=-math.inf, high=math.inf, low_open=False):
        value = self._require()
        if isinstance(value, bool) or not isinstance(value, (int, float)) or not math.isfinite(value):
            self.fail("expected a finite number, got %r" % (value,))
        value = float(value)
        if value < low or value > high or (low_open and value == low):
            self.fail("%g is outside %s%g, %g]" % (value, "(" if low_open else "[", low, high))
        return value

    def positive(self, high=math.inf):
        return self.number(0.0, high, low_open=True)

    def vector(self, n=None):
        value = self._require()
        if not isinstance(value, list) or (n is not None and len(value) != n):
            self.fail("expected a list of %s numbers" % (n if n is not None else "some"))
        return [Field(self.path, "%s[%d]" % (self.key, i), v).number() for i, v in enumerate(value)]

    def strings(self):
        value = self._require()
        if not isinstance(value, list) or not value:
            self.fail("expected a non-empty list of names")
        return [Field(self.path, "%s[%d]" % (self.key, i), v).string() for i, v in enumerate(value)]

    def color_bgr(self):
        bgr = self.vector(3)
        for i, c in enumerate(bgr):
            if c < 0 or c > 255:
                Field(self.path, "%s[%d]" % (self.key, i), c).fail("a colour channel must be 0..255")
        return bgr


def load(path):
    try:
        with open(path) as f:
            data = yaml.safe_load(f)
    except OSError as e:
        raise ConfigError("%s: cannot read the file (%s)" % (path, e.strerror))
    except yaml.YAMLError as e:
        raise ConfigError("%s: invalid YAML: %s" % (path, e))
    return Field(path, "", data)


# ----- URDF building -----------------------------------------------------------------------------

def fmt(values):
    # repr keeps every digit: the camera transforms must equal robot.yaml's to the last bit.
    return " ".join(repr(float(v)) for v in values)


class Urdf:
    def __init__(self, name):
        self.root = ET.Element("robot", name=name)
        self.links = set()
        self.joints = set()
        self.materials = set()

    def material(self, name, rgba):
        if name not in self.materials:
            m = ET.SubElement(self.root, "material", name=name)
            ET.SubElement(m, "color", rgba=fmt(rgba))
            self.materials.add(name)
        return name

    def link(self, name, where):
        if name in self.links:
            raise ConfigError("%s: link name '%s' is used twice" % (where, name))
        self.links.add(name)
        return ET.SubElement(self.root, "link", name=name)

    def visual(self, link, geometry, xyz=(0, 0, 0), rpy=(0, 0, 0), material=None):
        v = ET.SubElement(link, "visual")
        ET.SubElement(v, "origin", xyz=fmt(xyz), rpy=fmt(rpy))
        g = ET.SubElement(v, "geometry")
        kind, attrs = geometry
        ET.SubElement(g, kind, {k: fmt(val) if isinstance(val, (list, tuple)) else repr(float(val))
                                for k, val in attrs.items()})
        if material:
            ET.SubElement(v, "material", name=material)

    def joint(self, name, kind, parent, child, xyz, rpy, axis=None, where=""):
        if name in self.joints:
            raise ConfigError("%s: joint name '%s' is used twice" % (where, name))
        self.joints.add(name)
        j = ET.SubElement(self.root, "joint", name=name, type=kind)
        ET.SubElement(j, "parent", link=parent)
        ET.SubElement(j, "child", link=child)
        ET.SubElement(j, "origin", xyz=fmt(xyz), rpy=fmt(rpy))
        if axis is not None:
            ET.SubElement(j, "axis", xyz=fmt(axis))

    def rename_frames(self, root_link, prefix):
        """Renames the root link to root_link and every other link and joint to prefix + name, so that a
        second copy of a robot can stand in the same tf tree (the simulator's truth ghost of the target,
        rooted at its frame target_truth) without taking the first copy's frames."""
        links = [e.get("name") for e in self.root.findall("link")]
        children = {e.find("child").get("link") for e in self.root.findall("joint")}
        roots = [name for name in links if name not in children]
        if len(roots) != 1:
            raise ConfigError("cannot rename frames: the URDF has roots %s, not one" % roots)
        new_name = {name: (root_link if name == roots[0] else prefix + name) for name in links}
        for e in self.root.findall("link"):
            e.set("name", new_name[e.get("name")])
        for e in self.root.findall("joint"):
            e.set("name", prefix + e.get("name"))
            for end in ("parent", "child"):
                e.find(end).set("link", new_name[e.find(end).get("link")])
        self.links = set(new_name.values())

    def text(self, header):
        ET.indent(self.root)
        header = header.replace("--", "- -")  # "--" may not appear inside an XML comment
        return '<?xml version="1.0"?>\n<!-- %s -->\n%s\n' % (header, ET.tostring(self.root, encoding="unicode"))


def box(x, y, z):
    return ("box", {"size": (x, y, z)})


def cylinder(radius, length):
    return ("cylinder", {"radius": radius, "length": length})


def sphere(radius):
    return ("sphere", {"radius": radius})


def rgba_from_bgr(bgr):
    return (bgr[2] / 255.0, bgr[1] / 255.0, bgr[0] / 255.0, 1.0)


# ----- the target -------------------------------------------------------------------------------

class TargetModel:
    def __init__(self, target_file):
        t = target_file["target"]
        self.file = target_file.path
        self.frame_id = t["frame_id"].string()
        self.face_w = t["face"]["width_m"].positive(5.0)
        self.face_h = t["face"]["height_m"].positive(5.0)
        self.port_radius = t["port_radius_m"].positive(1.0)
        self.depth = t["body"]["depth_m"].positive(5.0)
        self.body_bgr = t["body"]["color_bgr"].color_bgr()
        panels = t["solar_panels"]
        self.panel_span = panels["span_m"].number(0.0, 5.0)
        self.panel_h = panels["height_m"].number(0.0, 5.0)
        self.panel_x = panels["offset_x_m"].number(-5.0, 0.0)
        self.panel_bgr = panels["color_bgr"].color_bgr()
        self.mount_xyz = t["mount"]["xyz_m"].vector(3)
        self.mount_yaw = t["mount"]["yaw_rad"].number(-2 * math.pi, 2 * math.pi)
        if self.mount_xyz[2] - self.face_h / 2 <= 0.0:
            t["mount"]["xyz_m"].fail("puts the bottom of the face (z %.3f - height/2) at or below the floor"
                                     % self.mount_xyz[2])


def target_urdf(target):
    u = Urdf("docking_target")
    w, h, d = target.face_w, target.face_h, target.depth
    body = u.material("target_body", rgba_from_bgr(target.body_bgr))
    panel = u.material("target_solar_panel", rgba_from_bgr(target.panel_bgr))
    face_colour = u.material("target_face", (0.9, 0.9, 0.9, 1.0))
    port_colour = u.material("target_port", (0.1, 0.1, 0.1, 1.0))
    base_colour = u.material("target_base", (0.24, 0.24, 0.24, 1.0))
    where = target.file

    # The port frame is the root: rviz draws the model wherever tf has `target` (estimated or true).
    u.link(target.frame_id, where)

    face = u.link("target_face_plate", where)
    # The face is the plane x = 0; the plate's thickness goes behind it, into the body.
    u.visual(face, box(FACE_PLATE_THICKNESS_M, w, h), xyz=(-FACE_PLATE_THICKNESS_M / 2, 0, 0), material=face_colour)
    u.visual(face, cylinder(target.port_radius, 0.002), xyz=(0.001, 0, 0), rpy=(0, math.pi / 2, 0),
             material=port_colour)
    u.joint("target_face_plate_joint", "fixed", target.frame_id, "target_face_plate", (0, 0, 0), (0, 0, 0),
            where=where)

    # The box from behind the plate to x = -depth (starting at x = 0 would put two surfaces in the face
    # plane, and rviz would flicker between them).
    body_link = u.link("target_body", where)
    body_depth = max(d - FACE_PLATE_THICKNESS_M, FACE_PLATE_THICKNESS_M)
    u.visual(body_link, box(body_depth, w, h), material=body)
    u.joint("target_body_joint", "fixed", target.frame_id, "target_body", (-d + body_depth / 2, 0, 0), (0, 0, 0),
            where=where)

    # Two flat wings beside the box in the plane x = offset_x_m, as the simulator renders them (none
    # when a size is zero: a zero-size box is not valid URDF).
    if target.panel_span > 0 and target.panel_h > 0:
        for side, name in ((1, "target_solar_panel_pos_y"), (-1, "target_solar_panel_neg_y")):
            link = u.link(name, where)
            u.visual(link, box(PANEL_THICKNESS_M, target.panel_span, target.panel_h), material=panel)
            u.joint(name + "_joint", "fixed", target.frame_id, name,
                    (target.panel_x, side * (w / 2 + target.panel_span / 2), 0), (0, 0, 0), where=where)

    # The target robot's base: target.yaml gives the port in the base frame (mount), so the base sits
    # at the inverse of the mount below the port.
    mx, my, mz = target.mount_xyz
    c, s = math.cos(target.mount_yaw), math.sin(target.mount_yaw)
    base_in_port = (-(c * mx + s * my), -(-s * mx + c * my), -mz)
    base = u.link("target_base_link", where)
    # A column under the mockup's body, from the floor to the bottom of the face (visual only).
    column_h = mz - h / 2
    cx, cy = mx + c * (-d / 2), my + s * (-d / 2)
    u.visual(base, box(d, w, column_h), xyz=(cx, cy, column_h / 2), rpy=(0, 0, target.mount_yaw),
             material=base_colour)
    u.joint("target_base_joint", "fixed", target.frame_id, "target_base_link", base_in_port,
            (0, 0, -target.mount_yaw), where=where)
    return u


# ----- the chaser -------------------------------------------------------------------------------

def chaser_urdf(robot_file, base_file, target):
    ch = robot_file["chaser"]
    base_frame = ch["base_frame"].string()
    footprint = ch["footprint_radius_m"].positive(2.0)
    probe_x = ch["docking_probe_x_m"].number(0.0, 2.0)

    wheels = base_file["wheels"]
    names = wheels["names"].strings()
    angles_deg = wheels["drive_angles_deg"].vector()
    if len(angles_deg) != len(names):
        wheels["drive_angles_deg"].fail("has %d angles for %d wheels (wheels.names)" % (len(angles_deg), len(names)))
    if len(names) < 3:
        wheels["names"].fail("an omni base needs at least 3 wheels")
    dist = wheels["center_distance_m"].positive(2.0)
    radius = wheels["radius_m"].positive(1.0)

    u = Urdf("docking_chaser")
    chassis = u.material("chaser_chassis", (0.3, 0.3, 0.32, 1.0))
    rubber = u.material("chaser_wheel", (0.1, 0.1, 0.1, 1.0))
    metal = u.material("chaser_probe", (0.8, 0.6, 0.2, 1.0))
    lens = u.material("chaser_camera", (0.05, 0.05, 0.3, 1.0))

    # base_link on the floor (REP 105, z up), at the base centre; the round chassis sits on the wheels.
    base = u.link(base_frame, robot_file.path)
    u.visual(base, cylinder(footprint, CHASSIS_THICKNESS_M), xyz=(0, 0, 2 * radius + CHASSIS_THICKNESS_M / 2),
             material=chassis)

    # Wheel i drives along angle a_i, so omni_base's kinematics (qdot_i = (cos a vx + sin a vy + L wz) / r)
    # puts it at L (sin a, -cos a), 90 deg clockwise of its drive direction: only there does a positive
    # wz move its contact point along +a. Joint frame: x along the drive direction; the axle is +y, so a
    # positive wheel angle rolls the base along +a, as a positive encoder count does.
    for i, (name, a_deg) in enumerate(zip(names, angles_deg)):
        a = math.radians(a_deg)
        link = u.link(name + "_link", "%s: wheels.names[%d]" % (base_file.path, i))
        u.visual(link, cylinder(radius, WHEEL_WIDTH_M), rpy=(math.pi / 2, 0, 0), material=rubber)
        u.joint(name, "continuous", base_frame, name + "_link", (dist * math.sin(a), -dist * math.cos(a), radius),
                (0, 0, a), axis=(0, 1, 0), where="%s: wheels.names[%d]" % (base_file.path, i))

    # The probe tip: robot.yaml gives its x; its height is the port's (target.yaml mount z), because
    # the tip meets the port centre when docked. The rod is drawn from the base centre to the tip.
    probe = u.link("docking_probe", robot_file.path)
    if probe_x > 0:
        u.visual(probe, cylinder(PROBE_ROD_RADIUS_M, probe_x), xyz=(-probe_x / 2, 0, 0), rpy=(0, math.pi / 2, 0),
                 material=metal)
    u.visual(probe, sphere(1.5 * PROBE_ROD_RADIUS_M), material=metal)
    u.joint("docking_probe_joint", "fixed", base_frame, "docking_probe", (probe_x, 0, target.mount_xyz[2]),
            (0, 0, 0), where=robot_file.path)

    # Cameras: each optical frame exactly as robot.yaml gives it (fixed-axis rpy, the URDF convention,
    # as camera_frames_publisher and the simulator read it).
    for key, cam in ch["cameras"].items():
        frame = cam["frame_id"].string()
        if frame == base_frame:
            cam["frame_id"].fail("equals the base frame")
        xyz = cam["xyz_m"].vector(3)
        rpy = cam["rpy_rad"].vector(3)
        link = u.link(frame, "%s: %s" % (robot_file.path, cam["frame_id"].key))
        u.visual(link, box(*CAMERA_BOX_M), xyz=(0, 0, -CAMERA_BOX_M[2] / 2), material=lens)
        u.joint(frame + "_joint", "fixed", base_frame, frame, xyz, rpy,
                where="%s: %s" % (robot_file.path, cam["frame_id"].key))
    return u


def main(argv):
    parser = argparse.ArgumentParser(description="Prints the chaser's or the target's URDF from the config YAML.")
    parser.add_argument("robot", choices=["chaser", "target"])
    parser.add_argument("--config-dir", default=None, help="folder of robot.yaml, omni_base.yaml, target.yaml")
    parser.add_argument("--robot", dest="robot_yaml", help="robot.yaml (default: CONFIG_DIR/robot.yaml)")
    parser.add_argument("--omni-base", dest="omni_base_yaml", help="omni_base.yaml (default: CONFIG_DIR/omni_base.yaml)")
    parser.add_argument("--target", dest="target_yaml", help="target.yaml (default: CONFIG_DIR/target.yaml)")
    parser.add_argument("--root-frame", help="rename the root link to this frame (e.g. target_truth: a ghost "
                                             "of the model at the simulator's truth)")
    parser.add_argument("--link-prefix", default="", help="with --root-frame: prefix of every other link and joint")
    # roslaunch appends __name:= and __log:= to commands it runs; they are not ours.
    args = parser.parse_args([a for a in argv if not a.startswith("__")])

    def path(explicit, name):
        if explicit:
            return explicit
        if args.config_dir is None:
            parser.error("give --config-dir or --%s" % name.replace("omni_base", "omni-base").replace(".yaml", ""))
        return os.path.join(args.config_dir, name)

    try:
        target = TargetModel(load(path(args.target_yaml, "target.yaml")))
        if args.robot == "target":
            urdf = target_urdf(target)
            header = "generated by docking_description/make_urdf.py from %s: do not edit" % target.file
        else:
            robot_path = path(args.robot_yaml, "robot.yaml")
            base_path = path(args.omni_base_yaml, "omni_base.yaml")
            urdf = chaser_urdf(load(robot_path), load(base_path), target)
            header = "generated by docking_description/make_urdf.py from %s, %s, %s: do not edit" % (
                robot_path, base_path, target.file)
        if args.root_frame:
            if not args.link_prefix:
                parser.error("--root-frame needs --link-prefix (the copy's frames must differ from the model's)")
            urdf.rename_frames(args.root_frame, args.link_prefix)
            header += " (frames renamed: root %s, others prefixed %s)" % (args.root_frame, args.link_prefix)
    except ConfigError as e:
        sys.stderr.write("make_urdf.py: %s\n" % e)
        return 2
    sys.stdout.write(urdf.text(header))
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
