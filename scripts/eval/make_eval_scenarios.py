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


def scenario_yaml(comment, description, duration_s, seed, lighting, x, y, yaw_deg, yaw_rate_deg_s, extra=None):
    """A scenario file's text (docking_sim's format): the chaser at the origin facing +x, the target
    robot at (x, y, yaw_deg) turning at yaw_rate_deg_s. `comment`: the header lines, without '#'.
    extra: the realistic camera's optional keys (chaser_motion, light_direction, extra_clutter,
    camera_overrides), see RealisticExtras, target_roll_deg (the target turned about its port's axis) and
    camera_tilt ((roll_deg, pitch_deg): the chaser's camera head mounted tilted, unknown to the stack)."""
    header = "".join(f"# {line}\n" for line in comment.splitlines())
    extra = extra or {}
    chaser_motion = ""
    roll = f"    roll_deg: {extra['target_roll_deg']:.1f}\n" if extra.get("target_roll_deg") else ""
    if extra.get("chaser_motion"):
        rate, reverse = extra["chaser_motion"]
        chaser_motion = f", motion: {{yaw_rate_deg_s: {rate:.3f}, reverse_every_s: {reverse:.3f}}}"
    if extra.get("camera_tilt"):
        tilt_roll, tilt_pitch = extra["camera_tilt"]
        chaser_motion += f", camera_tilt: {{roll_deg: {tilt_roll:.1f}, pitch_deg: {tilt_pitch:.1f}}}"
    text = f"""{header}scenario:
  description: "{description}"
  duration_s: {duration_s}
  seed: {seed}
  lighting: {lighting}
  chaser: {{x_m: 0.0, y_m: 0.0, yaw_deg: 0.0{chaser_motion}}}
  target:
    x_m: {x:.4f}
    y_m: {y:.4f}
    yaw_deg: {yaw_deg:.3f}
{roll}    motion: {{yaw_rate_deg_s: {yaw_rate_deg_s:.3f}, velocity_m_s: [0.0, 0.0]}}
"""
    if extra.get("light_direction"):
        d = extra["light_direction"]
        text += f"  light_direction: [{d[0]:.4f}, {d[1]:.4f}, {d[2]:.4f}]\n"
    if extra.get("extra_clutter"):
        text += "  extra_clutter:\n"
        for box in extra["extra_clutter"]:
            text += (f"    - {{name: {box['name']}, xy_m: [{box['x']:.3f}, {box['y']:.3f}], yaw_deg: {box['yaw']:.1f}, "
                     f"size_m: [{box['size'][0]}, {box['size'][1]}, {box['size'][2]}], material: {box['material']}, "
                     f"color_bgr: {box['color']}}}\n")
    if extra.get("camera_overrides"):
        text += "  camera_overrides:\n"
        for band, block in extra["camera_overrides"].items():
            text += f"    {band}: {block}\n"
    return text


def write(name, description, range_m, bearing, turn, lighting="nominal", yaw_rate=0.0, duration=14.0, seed=11,
          extra=None):
    x, y, yaw = target_pose(range_m, bearing, turn)
    text = scenario_yaml(f"Evaluation scenario (written by scripts/eval/make_eval_scenarios.py): {description}.",
                         description, duration, seed, lighting, x, y, yaw, yaw_rate, extra)
    (OUT / f"{name}.yaml").write_text(text)
    return name


# ---- The realistic set (issue 11): eval_real_*.yaml -----------------------------------------------
# Blur measured per scenario: `sim_render --config config --scenario NAME --time 1` prints, per
# camera, the target's defocus sigma, the residual blur, the motion blur length over the exposure,
# the exposure, the gain and the noise (see src/docking_sim/README.md). Seeds 21-40: none of them is
# a campaign seed.

FOCAL_PX = 550.0
# sim.yaml's C270 optics (3 mm, f/2.0, 5.6 um pixels): thin-lens defocus sigma = K |1/s - 1/z| s/(s - f).
C270_F_M, C270_APERTURE_M, C270_PITCH_M = 3e-3, 1.5e-3, 5.6e-6


def defocus_2px(range_m, sigma_px=2.0):
    """camera_overrides for the C270 with its lens screwed out (a user's close-up adjustment; f/2.0
    kept) so that the target at range_m is blurred by sigma_px: focused nearer, at s (a few cm)."""
    k = C270_APERTURE_M * C270_F_M / C270_PITCH_M / 4.0
    s = 1.0 / (1.0 / range_m + sigma_px / k)
    for _ in range(20):  # the s / (s - f) factor, by fixed point
        s = 1.0 / (1.0 / range_m + sigma_px / (k * s / (s - C270_F_M)))
    return f"{{optics: {{focus_distance_m: {s:.5f}}}}}"


# A dimmer room: the light of the nominal lighting at a 133 ms exposure, so auto-exposure runs at its
# 33 ms limit with gain up to 4: noise up to 2 DN x 4 = 8 DN, and 33 ms of motion blur.
DIM_NOISE_8DN = "{exposure_time_s: 0.133, auto_exposure: {max_gain: 4.0}}"
# A room that needs the longest exposure at gain 1 (33 ms): the motion-blur scenarios' exposure.
EXPOSURE_33MS = "{exposure_time_s: 0.0333}"


def turn_for_blur(blur_px, exposure_s, range_m, sweep_deg=8.0):
    """The chaser's scripted turn that smears the target's face by blur_px over exposure_s, reversing
    so the heading sweeps +-sweep_deg (the target stays in view). Rotation moves the image by f w T
    px; the camera sits ~0.10 m ahead of the turn axis (+ f w T 0.10 / range) and the face's corners
    lie off the axis (+ (0.15 / range)^2)."""
    rate = blur_px / (FOCAL_PX * exposure_s * (1.0 + 0.10 / range_m + (0.15 / range_m) ** 2))
    return math.degrees(rate), 2.0 * math.radians(sweep_deg) / rate


def clutter_around(range_m, bearing_deg, far=False):
    """Busy boxes at the target's depth: behind it, beside it left and right (clear of its 0.9 m span
    with the solar panels), and at far range one within 0.5 m of its depth 1.7 m to the side."""
    b = math.radians(bearing_deg)
    along = (math.cos(b), math.sin(b))
    left = (-math.sin(b), math.cos(b))

    def at(u, w):
        return CAMERA_X + u * along[0] + w * left[0], CAMERA_Y + u * along[1] + w * left[1]

    boxes = []
    for name, u, w, size, material, color in [
            ("busy_behind", range_m + 0.8, 0.25, [0.8, 0.8, 1.2], "busy", "[170, 160, 150]"),
            ("busy_left", range_m + 0.1, 0.8, [0.4, 0.4, 1.0], "photo", "[150, 170, 190]"),
            ("busy_right", range_m + 0.4, -0.85, [0.5, 0.5, 0.9], "busy", "[190, 170, 150]")]:
        x, y = at(u, w)
        boxes.append(dict(name=name, x=x, y=y, yaw=bearing_deg, size=size, material=material, color=color))
    if far:
        x, y = at(range_m + 0.3, 1.7)
        boxes.append(dict(name="far_distractor", x=x, y=y, yaw=bearing_deg + 10.0, size=[0.4, 0.4, 0.55],
                          material="busy", color="[160, 160, 160]"))
    return boxes


def port_frame(range_m, bearing, turn):
    """The port's centre (world) and its y (right of a viewer facing it) and z axes."""
    x, y, yaw_deg = target_pose(range_m, bearing, turn)
    yaw = math.radians(yaw_deg)
    centre = (x + PORT_AHEAD_OF_TARGET_CENTRE * math.cos(yaw), y + PORT_AHEAD_OF_TARGET_CENTRE * math.sin(yaw), 0.25)
    return centre, (-math.sin(yaw), math.cos(yaw), 0.0), (0.0, 0.0, 1.0), (math.cos(yaw), math.sin(yaw), 0.0)


def light_for_highlight(camera_xyz, face_point, normal):
    """The direction a distant light travels for its mirror reflection off the face at face_point to
    reach the camera: reflect the face->camera direction about the face normal, reversed."""
    r = [c - p for c, p in zip(camera_xyz, face_point)]
    n_r = math.sqrt(sum(v * v for v in r))
    r = [v / n_r for v in r]
    dot = sum(a * b for a, b in zip(r, normal))
    return [-(2 * dot * n - v) for v, n in zip(r, normal)]


def realistic():
    names = []
    c270 = "the C270 optics of sim.yaml (fixed focus 0.9 m, f/2.0)"
    names.append(write("eval_real_c270_0p4m", f"port 0.4 m ahead, {c270}: defocused at the near end", 0.4, 0.0, 10.0,
                       seed=21))
    names.append(write("eval_real_c270_2m_off", f"port 2 m, off-axis, {c270}", 2.0, 12.0, 25.0, seed=22))
    for r, seed in [(0.4, 23), (1.4, 24)]:
        names.append(write(f"eval_real_defocus2px_{r:g}m".replace(".", "p"),
                           f"port {r:g} m ahead, lens misfocused to 8 cm: defocus sigma ~2 px", r, 0.0, 10.0, seed=seed,
                           extra={"camera_overrides": {"visible": defocus_2px(r)}}))
    for blur, r, seed in [(5, 1.0, 25), (9, 1.0, 26), (9, 2.0, 27), (5, 4.0, 28)]:
        rate, reverse = turn_for_blur(blur, 0.0333, r)
        names.append(write(f"eval_real_motion{blur}px_{r:g}m".replace(".", "p"),
                           f"port {r:g} m ahead, the chaser turning +-{rate:.0f} deg/s with a 33 ms exposure: "
                           f"~{blur} px of motion blur", r, 0.0, 10.0, seed=seed,
                           extra={"chaser_motion": (rate, reverse), "camera_overrides": {"visible": EXPOSURE_33MS}}))
    names.append(write("eval_real_noise8_1p4m", "port 1.4 m ahead in a dim room: 33 ms, gain 4, noise 8 DN", 1.4, 0.0,
                       10.0, seed=29, extra={"camera_overrides": {"visible": DIM_NOISE_8DN}}))
    for r, seed in [(1.0, 30), (2.0, 31)]:
        names.append(write(f"eval_real_clutter_{r:g}m".replace(".", "p"),
                           f"port {r:g} m ahead among busy boxes at its depth", r, 0.0, 10.0, seed=seed,
                           extra={"extra_clutter": clutter_around(r, 0.0)}))
    names.append(write("eval_real_clutter_defocus2px_1m", "port 1 m ahead among busy boxes, defocus sigma ~2 px",
                       1.0, 0.0, 10.0, seed=32,
                       extra={"extra_clutter": clutter_around(1.0, 0.0),
                              "camera_overrides": {"visible": defocus_2px(1.0)}}))
    rate, reverse = turn_for_blur(9, 0.0333, 1.0)
    names.append(write("eval_real_clutter_motion9px_noise8_1m",
                       "port 1 m ahead among busy boxes, chaser turning (~9 px of motion blur), dim: noise 8 DN",
                       1.0, 0.0, 10.0, seed=33,
                       extra={"extra_clutter": clutter_around(1.0, 0.0), "chaser_motion": (rate, reverse),
                              "camera_overrides": {"visible": DIM_NOISE_8DN}}))
    for r, seed in [(4.0, 34), (6.0, 35)]:
        names.append(write(f"eval_real_clutter_far_{r:g}m".replace(".", "p"),
                           f"port {r:g} m ahead among busy boxes, one 1.7 m to the side within 0.5 m of its depth",
                           r, 0.0, 10.0, seed=seed, extra={"extra_clutter": clutter_around(r, 0.0, far=True)}))
    # A strong highlight on the glossy face at 2 m: a low light (a lamp behind the chaser; it also lights
    # the walls that face the camera) whose mirror reflection reaches the left camera 6 cm up and 5 cm
    # right of the port centre; it saturates a disc of ~4-5 cm radius of the face.
    centre, y_axis, z_axis, normal = port_frame(2.0, 0.0, 0.0)
    spot = [c + 0.05 * yy + 0.06 * zz for c, yy, zz in zip(centre, y_axis, z_axis)]
    names.append(write("eval_real_specular_2m", "port 2 m ahead, a strong specular highlight saturating part of the face",
                       2.0, 0.0, 0.0, seed=36,
                       extra={"light_direction": light_for_highlight((CAMERA_X, CAMERA_Y, 0.25), spot, normal),
                              "camera_overrides": {"visible": "{specular: {strength: 1.5, shininess: 20000.0}}",
                                                   "ir": "{specular: {strength: 1.5, shininess: 20000.0}}"}}))
    # In the dark, an IR reflection 2.5 cm beside LED 3 (target.yaml marker [0, -0.11, 0.01]) in the
    # IR camera (base 0.10, 0.0, 0.30): a saturated spot of ~7 px radius that merges with the LED's.
    centre, y_axis, z_axis, normal = port_frame(2.0, 0.0, 0.0)
    spot = [c + (-0.11 + 0.025) * yy + 0.01 * zz for c, yy, zz in zip(centre, y_axis, z_axis)]
    names.append(write("eval_real_dark_ir_reflection_2m",
                       "port 2 m ahead in the dark, an IR reflection on the face merging with one LED", 2.0, 0.0, 0.0,
                       lighting="dark", seed=37,
                       extra={"light_direction": light_for_highlight((0.10, 0.0, 0.30), spot, normal),
                              "camera_overrides": {"ir": "{specular: {strength: 20.0, shininess: 40000.0}}"}}))
    return names


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
    # Issue 57: a target not upright (a print glued at an angle, a ramp, orbit): rolled 20 deg, sharp, clean.
    names.append(write("eval_roll20_1m", "port 1 m ahead, the target rolled 20 deg about the port's axis",
                       1.0, 0.0, 10.0, seed=41, extra={"target_roll_deg": 20.0}))
    # ... and a camera head mounted with a tilt the stack does not know (robot.yaml keeps the nominal mounts).
    names.append(write("eval_tilt15_1p4m", "port 1.4 m ahead, the camera head mounted rolled 15 deg and pitched 3 deg",
                       1.4, 0.0, 10.0, seed=42, extra={"camera_tilt": (15.0, 3.0)}))
    names += realistic()
    print("\n".join(names))


if __name__ == "__main__":
    main()
