#!/usr/bin/env python3
"""The far-range stage's options measured side by side (issue 15): detection and error on the far scenes,
CPU time, and (with --instructions) instructions per frame under callgrind.

  scripts/eval/far_stage_options.py [--out results/far_stage_options.json] [--instructions]

For each scene (eval_far_* and the cluttered far ones) the simulator renders one raw stereo pair and the
truth (sim_render); bench_disparity runs the far stage on it in each configuration:
  deployed      640x480, 96 disparities (config/stereo_image_proc.yaml: perception.launch)
  full_48       640x480, 48 disparities (the far stage needs d <= 27.5 px beyond 2 m; 48 reach 1.15 m)
  window        the tracking window (config/far_stereo.yaml window_*), 96 disparities
The error is the detection's distance to the port's true position (the target origin). A program that
prints figures; nothing here asserts.
"""
import argparse
import json
import pathlib
import re
import subprocess
import sys
import tempfile

ROOT = pathlib.Path(__file__).resolve().parents[2]
BENCH = ROOT / "devel" / "lib" / "docking_perception" / "bench_disparity"
RENDER = ROOT / "devel" / "lib" / "docking_sim" / "sim_render"
SCENES = ["eval_far_2m_on", "eval_far_2m_off", "eval_far_3m_on", "eval_far_3m_off", "eval_far_4m_on",
          "eval_far_4m_off", "eval_far_6m_on", "eval_far_6m_off", "eval_real_clutter_far_4m",
          "eval_real_clutter_far_6m"]
CONFIGS = {"deployed": [], "full_48": ["--disparity-range", "48"], "window": ["--window"]}
FRAMES = 10
DETECTION = re.compile(r"detection on .*?: (found|NOT found: (?P<reason>[^,]*)).*?position \((?P<x>[-\d.e]+), "
                       r"(?P<y>[-\d.e]+), (?P<z>[-\d.e]+)\) m")
TOTAL_MS = re.compile(r"disparity_total\s+([\d.]+) ms median")


def render(scene, folder):
    prefix = folder / scene
    subprocess.run([RENDER, "--config", ROOT / "config", "--scenario", scene, "--time", "1.0", "--out", prefix],
                   check=True, capture_output=True)
    subprocess.run([RENDER, "--config", ROOT / "config", "--scenario", scene, "--time", "1.0", "--sequence", "1",
                    "--out", folder / (scene + "_truth")], check=True, capture_output=True)
    truth = json.loads((folder / (scene + "_truth") / "sequence.json").read_text())["frames"][0]["position_m"]
    return f"{prefix}_stereo_left.png", f"{prefix}_stereo_right.png", truth


def run_config(left, right, extra, folder):
    out = subprocess.run([BENCH, folder / "bench.json", "--frames", str(FRAMES), "--config-dir", ROOT / "config",
                          "--left", left, "--right", right] + extra, check=True, capture_output=True, text=True).stdout
    found = DETECTION.search(out)
    total = TOTAL_MS.search(out)
    if not found or not total:
        raise RuntimeError("bench_disparity printed no detection or time:\n" + out)
    position = [float(found.group(k)) for k in "xyz"]
    return {"found": found.group(1) == "found", "reason": found.group("reason") or "", "position_m": position,
            "ms": float(total.group(1))}


def instructions(left, right, extra, folder):
    """Instructions per frame of rectify + disparity + detection, callgrind (6 frames with the warm-up)."""
    total = 0
    for function in ("*rectifyPair*", "docking_perception::disparity::testing::computeDisparity*",
                     "docking_perception::disparity::DisparityDetector::detect*"):
        run = subprocess.run(["valgrind", "--tool=callgrind", f"--callgrind-out-file={folder / 'cg.out'}",
                              f"--toggle-collect={function}", BENCH, folder / "bench.json", "--frames", "3",
                              "--config-dir", ROOT / "config", "--left", left, "--right", right] + extra,
                             capture_output=True, text=True)
        total += int(re.search(r"Collected\s*:\s*(\d+)", run.stderr).group(1))
    return round(total / 6 / 1e6, 1)


def main():
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--out", default=str(ROOT / "results" / "far_stage_options.json"))
    parser.add_argument("--instructions", action="store_true", help="also count instructions (callgrind, ~2 min)")
    args = parser.parse_args()
    results = {name: {} for name in CONFIGS}
    with tempfile.TemporaryDirectory() as tmp:
        folder = pathlib.Path(tmp)
        counted = {}
        for scene in SCENES:
            left, right, truth = render(scene, folder)
            for name, extra in CONFIGS.items():
                r = run_config(left, right, extra, folder)
                r["error_m"] = sum((a - b) ** 2 for a, b in zip(r["position_m"], truth)) ** 0.5 if r["found"] else None
                r["truth_m"] = truth
                results[name][scene] = r
                if args.instructions and scene == "eval_far_3m_on":
                    counted[name] = instructions(left, right, extra, folder)
    print(f"{'config':10s} {'found':>6s} {'error median mm':>16s} {'error max mm':>13s} {'ms median':>10s} "
          f"{'M instr/frame':>14s}  misses")
    summary = {}
    for name, scenes in results.items():
        errors = sorted(r["error_m"] for r in scenes.values() if r["found"])
        times = sorted(r["ms"] for r in scenes.values())
        misses = [f"{s} ({r['reason'][:60]})" for s, r in scenes.items() if not r["found"]]
        summary[name] = {"found": len(errors), "scenes": len(scenes),
                         "error_median_m": errors[len(errors) // 2] if errors else None,
                         "error_max_m": errors[-1] if errors else None, "ms_median": times[len(times) // 2],
                         "instructions_per_frame_M": counted.get(name), "misses": misses}
        s = summary[name]
        print(f"{name:10s} {s['found']:>3d}/{s['scenes']:<2d} "
              f"{(1000 * s['error_median_m']) if errors else float('nan'):16.1f} "
              f"{(1000 * s['error_max_m']) if errors else float('nan'):13.1f} {s['ms_median']:10.2f} "
              f"{s['instructions_per_frame_M'] if s['instructions_per_frame_M'] is not None else '-':>14}  "
              f"{'; '.join(misses)}")
    pathlib.Path(args.out).parent.mkdir(parents=True, exist_ok=True)
    pathlib.Path(args.out).write_text(json.dumps({"summary": summary, "scenes": results}, indent=2) + "\n")
    print(f"wrote {args.out}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
