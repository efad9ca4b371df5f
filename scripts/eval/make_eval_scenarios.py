#!/usr/bin/env python3
"""Writes the evaluation scenarios (config/scenarios/eval_*.yaml): a still target at a known range
from the left camera, on the optical axis or off it. Run again after changing the geometry below;
the files are committed so that `make eval` needs nothing generated.

Geometry (config/robot.yaml, config/target.yaml): the chaser sits at the world origin facing +x, its
left camera at base (0.10, 0.05, 0.25); the docking port is 0.15 m in front of the target robot's
centre at the camera's height. `range` is the camera-to-port distance at the start.
"""
import math
import pathlib

CAMERA_X, CAMERA_Y = 0.10, 0.05
PORT_AHEAD_OF_TARGET_CENTRE = 0.15
OUT = pathlib.Path(__file__).resolve().parents[2] / "config" / "scenarios"

# name suffix -> (bearing of the port seen from the camera [deg, + = left], port turned away from
# the camera [deg])
PLACEMENTS = {"on": (0.0, 0.0), "off": (12.0, 25.0)}
FAR_RANGES = [2.0, 3.0, 4.0, 6.0]
NEAR_RANGES = [0.4, 0.7, 1.0, 1.4, 2.0]


def robot_centre_for_port(port_x, port_y, yaw_rad):
    """The target robot's centre for a port at (port_x, port_y) whose axis points along yaw_rad."""
    return (port_x - PORT_AHEAD_OF_TARGET_CENTRE * math.cos(yaw_rad),
            port_y - PORT_AHEAD_OF_TARGET_CENTRE * math.sin(yaw_rad))


def target_pose(range_m, bearing_deg, port_turn_deg):
    b = math.radians(bearing_deg)
    port_x = CAMERA_X + range_m * math.cos(b)
    port_y = CAMERA_Y + range_m * math.sin(b)
    # The port's axis points back at the camera, then turned away by port_turn_deg.
    yaw = math.atan2(CAMERA_Y - port_y, CAMERA_X - port_x) + math.radians(port_turn_deg)
    x, y = robot_centre_for_port(port_x, port_y, yaw)
    return x, y, math.degrees(yaw)


def scenario_yaml(comment, description, duration_s, seed, lighting, x, y, yaw_deg, yaw_rate_deg_s):
    """A scenario file's text (docking_sim's format): the chaser at the origin facing +x, the target
    robot at (x, y, yaw_deg) turning at yaw_rate_deg_s. `comment`: the header lines, without '#'."""
    header = "".join(f"# {line}\n" for line in comment.splitlines())
    return f"""{header}scenario:
  description: "{description}"
  duration_s: {duration_s}
  seed: {seed}
  lighting: {lighting}
  chaser: {{x_m: 0.0, y_m: 0.0, yaw_deg: 0.0}}
  target:
    x_m: {x:.4f}
    y_m: {y:.4f}
    yaw_deg: {yaw_deg:.3f}
    motion: {{yaw_rate_deg_s: {yaw_rate_deg_s:.3f}, velocity_m_s: [0.0, 0.0]}}
"""


def write(name, description, range_m, bearing, turn, lighting="nominal", yaw_rate=0.0, duration=14.0, seed=11):
    x, y, yaw = target_pose(range_m, bearing, turn)
    text = scenario_yaml(f"Evaluation scenario (written by scripts/eval/make_eval_scenarios.py): {description}.",
                         description, duration, seed, lighting, x, y, yaw, yaw_rate)
    (OUT / f"{name}.yaml").write_text(text)
    return name


def main():
    names = []
    for r in FAR_RANGES:
        for place, (bearing, turn) in PLACEMENTS.items():
            names.append(write(f"eval_far_{r:g}m_{place}".replace(".", "p"),
                               f"still target, port {r:g} m from the left camera, {place}-axis", r, bearing, turn))
    for r in NEAR_RANGES:
        for place, (bearing, turn) in PLACEMENTS.items():
            names.append(write(f"eval_near_{r:g}m_{place}".replace(".", "p"),
                               f"still target, port {r:g} m from the left camera, {place}-axis", r, bearing, turn))
    names.append(write("eval_rotating_1m", "port 1 m ahead, target rotating at 3 deg/s (the paper's test)",
                       1.0, 0.0, -15.0, yaw_rate=3.0, duration=14.0))
    names.append(write("eval_dark_1m", "port 1 m ahead in the dark: only the IR LEDs are visible", 1.0, 0.0, 10.0,
                       lighting="dark"))
    names.append(write("eval_glare_1m", "port 1 m ahead with glare on the visible cameras", 1.0, 0.0, 10.0,
                       lighting="glare"))
    print("\n".join(names))


if __name__ == "__main__":
    main()
