#!/usr/bin/env python3
"""Monocular pose against AprilTag 3 on the same rendered frames (issue 5, "Evaluation").

For each scenario, sim_render (docking_sim) renders a sequence of the left camera as the visible
mono_pose instance sees it (grey, rectified like image_proc) twice with the same poses and noise seed:
with the normal target (config/target.yaml) and with the tagged variant (config/target_tagged.yaml).
compare_mono then runs our estimator (paper_5point and pnp; velocity by the Kalman filter and by frame
difference) on the first and AprilTag 3 (tag36h11, estimate_tag_pose) on the second, against the
truth. Writes results/eval/mono_comparison.json and prints a table. No ROS master needed.

Usage: scripts/eval/mono_comparison.py [--devel devel] [--frames 90] [--out results/eval/mono_comparison.json]
"""
import argparse
import json
import os
import pathlib
import shutil
import subprocess
import sys
import time

ROOT = pathlib.Path(__file__).resolve().parents[2]
# Ranges on axis, one off-axis view, the rotating target (velocities), a rolled target and a tilted camera.
SCENARIOS = [
    "eval_near_0p4m_on",
    "eval_near_0p7m_on",
    "eval_near_1m_on",
    "eval_near_1p4m_on",
    "eval_near_2m_on",
    "eval_near_1m_off",
    "eval_rotating_1m",
    "eval_roll20_1m",
    "eval_tilt15_1p4m",
]
METHODS = ["paper_5point", "pnp", "pnp_cold", "apriltag"]  # pnp_cold: each frame alone (no track, no hint)


def run(cmd):
    proc = subprocess.run([str(c) for c in cmd], cwd=ROOT, capture_output=True, text=True)
    if proc.returncode != 0:
        sys.stderr.write(proc.stdout + proc.stderr)
        raise SystemExit(f"failed: {' '.join(str(c) for c in cmd)}")
    return proc.stdout


def fmt(v, spec):
    return "-" if v is None else format(v, spec)


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--devel", default=str(ROOT / "devel"), help="catkin devel space holding the tools")
    ap.add_argument("--frames", type=int, default=90, help="frames per scenario (30 Hz)")
    ap.add_argument("--start", type=float, default=1.0, help="sim time of the first frame, s")
    ap.add_argument("--out", default=str(ROOT / "results/eval/mono_comparison.json"))
    ap.add_argument("--keep-frames", action="store_true", help="keep the rendered frames beside the output")
    ap.add_argument("--scenarios", nargs="*", default=SCENARIOS)
    args = ap.parse_args()

    devel = pathlib.Path(args.devel)
    sim_render = devel / "lib/docking_sim/sim_render"
    compare = devel / "lib/docking_perception/compare_mono"
    for tool in (sim_render, compare):
        if not os.access(tool, os.X_OK):
            raise SystemExit(f"{tool} not built (make build, or pass --devel)")
    out = pathlib.Path(args.out)
    work = out.parent / "mono_comparison_frames"
    out.parent.mkdir(parents=True, exist_ok=True)
    results = {}
    t0 = time.time()
    for sc in args.scenarios:
        folder = work / sc
        shutil.rmtree(folder, ignore_errors=True)
        folder.mkdir(parents=True)
        common = ["--config", ROOT / "config", "--scenario", sc, "--sequence", args.frames,
                  "--dt", 1.0 / 30.0, "--time", args.start]
        run([sim_render, *common, "--out", folder / "plain"])
        run([sim_render, *common, "--target", ROOT / "config/target_tagged.yaml", "--out", folder / "tagged"])
        print(run([compare, "--sequence", folder / "plain", "--tagged-sequence", folder / "tagged",
                   "--target", ROOT / "config/target.yaml", "--tagged-target", ROOT / "config/target_tagged.yaml",
                   "--mono-config", ROOT / "config/mono_pose_visible.yaml", "--out", folder / "compare.json"]),
              end="", flush=True)
        results[sc] = json.loads((folder / "compare.json").read_text())
    if not args.keep_frames:
        shutil.rmtree(work, ignore_errors=True)

    summary = {
        "what": "mono_pose (paper_5point, pnp) on config/target.yaml and AprilTag 3 (tag36h11, "
                "estimate_tag_pose, tag -> target) on config/target_tagged.yaml, same rendered poses, "
                "noise seed and camera; left camera rectified as image_proc does; one thread",
        "frames_per_scenario": args.frames,
        "rate_hz": 30.0,
        "scenarios": results,
    }
    out.write_text(json.dumps(summary, indent=2))

    print(f"\n{'scenario':19s} {'range':>6s} {'off':>5s} {'method':13s} {'found':>6s} {'pos med':>8s} "
          f"{'%range':>7s} {'pos p95':>8s} {'z bias':>7s} {'rot med':>8s} {'rot p95':>8s} {'ms':>6s}")
    for sc, r in results.items():
        for m in METHODS:
            d = r["methods"].get(m)
            if d is None:
                continue
            print(f"{sc:19s} {r['range_m']:6.2f} {r['face_off_axis_deg']:5.1f} {m:13s} "
                  f"{100 * d['detection_rate']:5.0f}% {fmt(d['position_error_m']['median'], '8.4f')} "
                  f"{fmt(d['position_error_pct_of_range']['median'], '7.3f')} "
                  f"{fmt(d['position_error_m']['p95'], '8.4f')} "
                  f"{fmt(None if d['detection_rate'] == 0 else d['position_bias_xyz_m'][2], '7.4f')} "
                  f"{fmt(d['orientation_error_deg']['median'], '8.3f')} "
                  f"{fmt(d['orientation_error_deg']['p95'], '8.3f')} {fmt(d['ms_per_frame']['median'], '6.2f')}"
                  + (f"  ({max(d['failures'], key=d['failures'].get)})" if d.get("failures") else ""))
    print("(m, deg, ms of thread CPU per frame; z bias = signed mean error along the optical axis, m)")
    print("\nvelocity errors (median over frames with a valid velocity): linear m/s, angular deg/s")
    for sc, r in results.items():
        print(f"{sc} (true |v| {r['true_speed_m_s']:.4f} m/s, |w| {r['true_angular_speed_deg_s']:.2f} deg/s)")
        for m in METHODS:
            for vm, v in r["methods"].get(m, {}).get("velocity", {}).items():
                print(f"  {m:13s} {vm:17s} valid {100 * v['valid_rate']:5.0f}%  linear "
                      f"{fmt(v['linear_error_m_s_median'], '.4f')}  angular {fmt(v['angular_error_deg_s_median'], '.3f')}")
    print(f"\nwrote {out} ({time.time() - t0:.0f} s)")


if __name__ == "__main__":
    main()
