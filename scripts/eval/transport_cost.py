#!/usr/bin/env python3
"""What the `compressed` image transport costs (issue 10, two computers): bytes on the link, and how far
JPEG moves the estimates.

1. sim_render (docking_sim) renders the three raw camera images (stereo pair bgr8, IR mono8, as the
   cameras publish them) of fixed scenarios at 15 Hz, --frames frames each (the simulator's noise is
   seeded: the frames are the same on every run).
2. image_codec (docking_image_transport: the plugin's own codec) encodes every frame at each setting
   (JPEG qualities, PNG), decodes it as the subscriber would, and reports the bytes and CPU times.
3. pipeline_on_frames (docking_perception) runs perception.launch's image path (rectify, disparity +
   detector, mono_pose visible and IR) on the raw frames and on each decoded set.
4. Per setting: bytes per frame and MB/s at 15 Hz, and per estimator the detection rate and the
   difference between the estimate on the decoded frames and on the raw ones (position mm, % of range,
   orientation deg).
Writes results/eval/transport_cost.json and prints the tables. No ROS master needed.

Usage: scripts/eval/transport_cost.py [--devel devel] [--frames 20] [--qualities 95 90 80 70]
"""
import argparse
import json
import math
import pathlib
import shutil
import subprocess
import sys
import time

ROOT = pathlib.Path(__file__).resolve().parents[2]
sys.path.insert(0, str(pathlib.Path(__file__).resolve().parent))
from eval_recorder import percentile  # noqa: E402  (one percentile for eval, demo and campaign)
from mono_comparison import fmt, run  # noqa: E402  (one way to run a tool, one way to print a figure)
# Near range for the two mono_pose instances, far range for the disparity detector, and the dark
# approach where only the IR instance sees the target.
SCENARIOS = [
    "eval_near_0p7m_on", "eval_near_1m_on", "eval_near_1p4m_on", "eval_near_2m_on", "eval_near_1m_off",
    "eval_far_2m_on", "eval_far_3m_on", "eval_far_4m_on", "eval_far_6m_on",
    "eval_dark_1m",
]
CAMERAS = ["stereo_left", "stereo_right", "ir"]
ESTIMATORS = ["disparity", "mono_visible", "mono_ir"]
RATE_HZ = 15.0


def angle_deg(qa, qb):
    """Rotation angle between two unit quaternions (x, y, z, w)."""
    dot = abs(sum(a * b for a, b in zip(qa, qb)))
    return math.degrees(2.0 * math.acos(min(1.0, dot)))


def compare(raw, coded):
    """Estimates on decoded frames against the same estimator on the raw frames, over all frames."""
    out = {}
    for est in ESTIMATORS:
        n = len(raw)
        valid_raw = sum(1 for r in raw if r[est]["valid"])
        valid_coded = sum(1 for c in coded if c[est]["valid"])
        pos_mm, pct, rot = [], [], []
        for r, c in zip(raw, coded):
            a, b = r[est], c[est]
            if not (a["valid"] and b["valid"]):
                continue
            d = math.dist(a["position_m"], b["position_m"])
            pos_mm.append(1e3 * d)
            pct.append(100.0 * d / math.hypot(*a["position_m"]))
            if "quaternion_xyzw" in a:
                rot.append(angle_deg(a["quaternion_xyzw"], b["quaternion_xyzw"]))
        out[est] = {
            "frames": n, "valid_raw": valid_raw, "valid_coded": valid_coded, "valid_both": len(pos_mm),
            "position_diff_mm": {"median": percentile(pos_mm, 50), "p95": percentile(pos_mm, 95),
                                 "max": max(pos_mm) if pos_mm else None},
            "position_diff_pct_of_range": {"median": percentile(pct, 50), "p95": percentile(pct, 95),
                                           "max": max(pct) if pct else None},
            "orientation_diff_deg": {"median": percentile(rot, 50), "p95": percentile(rot, 95),
                                     "max": max(rot) if rot else None},
        }
    return out


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--devel", default=str(ROOT / "devel"), help="catkin devel space holding the tools")
    ap.add_argument("--frames", type=int, default=20, help="frames per scenario (15 Hz)")
    ap.add_argument("--start", type=float, default=1.0, help="sim time of the first frame, s")
    ap.add_argument("--qualities", type=int, nargs="*", default=[95, 90, 80, 70])
    ap.add_argument("--png-level", type=int, default=3)
    ap.add_argument("--scenarios", nargs="*", default=SCENARIOS)
    ap.add_argument("--out", default=str(ROOT / "results/eval/transport_cost.json"))
    ap.add_argument("--keep-frames", action="store_true")
    args = ap.parse_args()

    devel = pathlib.Path(args.devel)
    sim_render = devel / "lib/docking_sim/sim_render"
    codec = devel / "lib/docking_image_transport/image_codec"
    pipeline = devel / "lib/docking_perception/pipeline_on_frames"
    for tool in (sim_render, codec, pipeline):
        if not tool.exists():
            raise SystemExit(f"{tool} not built")
    out = pathlib.Path(args.out)
    work = out.parent / "transport_cost_frames"
    shutil.rmtree(work, ignore_errors=True)
    t0 = time.time()

    # 1. Raw frames.
    prefixes = {}
    for sc in args.scenarios:
        folder = work / "raw" / sc
        folder.mkdir(parents=True)
        prefixes[sc] = []
        for k in range(args.frames):
            prefix = folder / f"f{k:04d}"
            run([sim_render, "--config", ROOT / "config", "--scenario", sc,
                 "--time", f"{args.start + k / RATE_HZ:.6f}", "--out", prefix])
            prefixes[sc].append(prefix)
    print(f"rendered {len(args.scenarios)} x {args.frames} frames ({time.time() - t0:.0f} s)", flush=True)

    settings = [(f"jpeg{q}", ["--format", "jpeg", "--quality", q]) for q in args.qualities]
    settings.append((f"png{args.png_level}", ["--format", "png", "--level", args.png_level]))

    def estimates(root):
        result = {}
        for sc in args.scenarios:
            lines = run([pipeline, "--config", ROOT / "config", "--dt", 1.0 / RATE_HZ,
                         *[root / sc / p.name for p in prefixes[sc]]])
            result[sc] = [json.loads(line) for line in lines.splitlines() if line.strip()]
        return result

    raw_est = estimates(work / "raw")
    print(f"perception on raw frames done ({time.time() - t0:.0f} s)", flush=True)

    # 2-4. Each setting.
    summary = {}
    for name, opts in settings:
        sizes = {cam: [] for cam in CAMERAS}
        enc_ms = {cam: [] for cam in CAMERAS}
        dec_ms = {cam: [] for cam in CAMERAS}
        for sc in args.scenarios:
            folder = work / name / sc
            folder.mkdir(parents=True)
            files = [f"{p}_{cam}.png" for p in prefixes[sc] for cam in CAMERAS]
            for line in run([codec, *opts, "--out-dir", folder, *files]).splitlines():
                rec = json.loads(line)
                cam = next(c for c in CAMERAS if rec["file"].endswith(f"_{c}.png"))
                sizes[cam].append(rec["bytes"])
                enc_ms[cam].append(rec["encode_ms"])
                dec_ms[cam].append(rec["decode_ms"])
        coded_est = estimates(work / name)
        all_raw = [f for sc in args.scenarios for f in raw_est[sc]]
        all_coded = [f for sc in args.scenarios for f in coded_est[sc]]
        mean_bytes = {cam: sum(v) / len(v) for cam, v in sizes.items()}
        summary[name] = {
            "bytes_per_frame_mean": mean_bytes,
            "bytes_per_frame_max": {cam: max(v) for cam, v in sizes.items()},
            "mb_per_s_at_15hz_all_three": sum(mean_bytes.values()) * RATE_HZ / 1e6,
            "encode_ms_median": {cam: percentile(v, 50) for cam, v in enc_ms.items()},
            "decode_ms_median": {cam: percentile(v, 50) for cam, v in dec_ms.items()},
            "estimates_vs_raw": compare(all_raw, all_coded),
            "per_scenario": {sc: compare(raw_est[sc], coded_est[sc]) for sc in args.scenarios},
        }
        print(f"{name} done ({time.time() - t0:.0f} s)", flush=True)

    raw_bytes = {"stereo_left": 640 * 480 * 3, "stereo_right": 640 * 480 * 3, "ir": 640 * 480}
    result = {
        "what": "three raw camera images per frame from sim_render (stereo bgr8, IR mono8, 640x480), encoded "
                "and decoded with docking_image_transport's codec, perception (pipeline_on_frames) on raw and "
                "decoded frames; differences are decoded minus raw, frames where both are valid",
        "scenarios": args.scenarios, "frames_per_scenario": args.frames, "rate_hz": RATE_HZ,
        "raw": {"bytes_per_frame": raw_bytes, "mb_per_s_at_15hz_all_three": sum(raw_bytes.values()) * RATE_HZ / 1e6},
        "raw_detection": {est: sum(1 for sc in args.scenarios for f in raw_est[sc] if f[est]["valid"])
                          for est in ESTIMATORS},
        "raw_estimates": raw_est,
        "settings": summary,
    }
    out.parent.mkdir(parents=True, exist_ok=True)
    out.write_text(json.dumps(result, indent=1))
    if not args.keep_frames:
        shutil.rmtree(work, ignore_errors=True)

    print(f"\n{'setting':8s} {'left B':>8s} {'right B':>8s} {'IR B':>8s} {'MB/s@15Hz':>10s} "
          f"{'enc ms L/IR':>12s} {'dec ms L/IR':>12s}")
    print(f"{'raw':8s} {raw_bytes['stereo_left']:8d} {raw_bytes['stereo_right']:8d} {raw_bytes['ir']:8d} "
          f"{result['raw']['mb_per_s_at_15hz_all_three']:10.2f}")
    for name, s in summary.items():
        b = s["bytes_per_frame_mean"]
        print(f"{name:8s} {b['stereo_left']:8.0f} {b['stereo_right']:8.0f} {b['ir']:8.0f} "
              f"{s['mb_per_s_at_15hz_all_three']:10.2f} "
              f"{s['encode_ms_median']['stereo_left']:5.1f}/{s['encode_ms_median']['ir']:5.1f} "
              f"{s['decode_ms_median']['stereo_left']:5.1f}/{s['decode_ms_median']['ir']:5.1f}")
    print(f"\n{'setting':8s} {'estimator':13s} {'valid raw/coded/n':>18s} {'pos med mm':>10s} {'p95':>7s} "
          f"{'max':>7s} {'max %rng':>8s} {'rot med':>8s} {'p95':>6s} {'max':>6s}")
    for name, s in summary.items():
        for est, e in s["estimates_vs_raw"].items():
            p, pc, r = e["position_diff_mm"], e["position_diff_pct_of_range"], e["orientation_diff_deg"]
            print(f"{name:8s} {est:13s} {e['valid_raw']:6d}/{e['valid_coded']:4d}/{e['frames']:4d}   "
                  f"{fmt(p['median'], '10.2f')} {fmt(p['p95'], '7.2f')} {fmt(p['max'], '7.2f')} "
                  f"{fmt(pc['max'], '8.3f')} {fmt(r['median'], '8.3f')} {fmt(r['p95'], '6.3f')} {fmt(r['max'], '6.3f')}")
    print(f"\nwrote {out} ({time.time() - t0:.0f} s)")


if __name__ == "__main__":
    main()
