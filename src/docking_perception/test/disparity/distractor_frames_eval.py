#!/usr/bin/env python3
"""Wrong valid estimates of the disparity detector on rendered frames of the simulator's scenarios.

For each scenario, renders the raw stereo pair N times (docking_sim's sim_render, at times spread over
the scenario's duration; sim_render draws one frame per run, so frame k uses the scenario's seed + k for
a new noise draw and new room textures, the geometry unchanged), the truth at the same time (--sequence 1: the port in the rectified left optical frame),
and runs bench_disparity on the pair (rectify + the matcher of stereo_image_proc.yaml + the detector of
disparity_detector.yaml, one frame: no track gate). Counts per scenario: found within 5 % of the range
(right), found farther off (wrong: the detector must never do that), and the outcomes of the rest.

  distractor_frames_eval.py --devel DEVEL_LIB_DIR --config CONFIG_DIR [--frames N] [--work DIR]
                            SCENARIO...
"""
import argparse
import collections
import json
import math
import os
import re
import shutil
import subprocess
import sys

import yaml


def run(cmd):
    return subprocess.run(cmd, check=True, capture_output=True, text=True).stdout


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--devel", required=True)
    ap.add_argument("--config", required=True)
    ap.add_argument("--frames", type=int, default=30)
    ap.add_argument("--detector-config", help="config folder of the detector and matcher (default --config)")
    ap.add_argument("--work", default="/tmp/distractor_frames_eval")
    ap.add_argument("--keep", action="store_true", help="keep the rendered pairs (else only the last)")
    ap.add_argument("scenarios", nargs="+")
    a = ap.parse_args()
    os.makedirs(a.work, exist_ok=True)
    config = os.path.join(a.work, "config")
    shutil.rmtree(config, ignore_errors=True)
    shutil.copytree(a.config, config)
    sim_render = os.path.join(a.devel, "docking_sim", "sim_render")
    bench = os.path.join(a.devel, "docking_perception", "bench_disparity")
    grand = collections.Counter()
    for name in a.scenarios:
        with open(os.path.join(a.config, "scenarios", name + ".yaml")) as f:
            scenario = yaml.safe_load(f)
        duration = float(scenario["scenario"].get("duration_s", 10.0))
        base_seed = int(scenario["scenario"].get("seed", 1))
        counts = collections.Counter()
        errors = []
        for k in range(a.frames):
            t = 0.5 + (duration - 1.0) * k / max(1, a.frames - 1)
            prefix = os.path.join(a.work, "%s_%02d" % (name, k) if a.keep else name)
            scenario["scenario"]["seed"] = base_seed + k
            with open(os.path.join(config, "scenarios", name + ".yaml"), "w") as f:
                yaml.safe_dump(scenario, f)
            run([sim_render, "--config", config, "--scenario", name, "--time", "%.3f" % t, "--out", prefix])
            seq = prefix + "_seq"
            run([sim_render, "--config", config, "--scenario", name, "--time", "%.3f" % t, "--sequence", "1",
                 "--out", seq])
            truth = json.load(open(os.path.join(seq, "sequence.json")))["frames"][0]["position_m"]
            out = run([bench, os.path.join(a.work, "bench.json"), "--frames", "1", "--config-dir", a.detector_config or a.config,
                       "--left", prefix + "_stereo_left.png", "--right", prefix + "_stereo_right.png"])
            found = "detection on" in out and ": found" in out
            pos = [float(v) for v in re.search(r"position \(([-\d.e]+), ([-\d.e]+), ([-\d.e]+)\)", out).groups()]
            outcome = re.search(r"outcome (\w+)", out).group(1)
            rng = math.sqrt(sum(v * v for v in truth))
            err = math.sqrt(sum((p - q) ** 2 for p, q in zip(pos, truth)))
            if found and err <= 0.05 * rng:
                verdict = "right"
            elif found:
                verdict = "WRONG"
                errors.append(err)
            else:
                verdict = outcome
            counts[verdict] += 1
            print("  %s t %.2f range %.2f: %-18s err %.2f m  %s" % (
                name, t, rng, verdict, err, out.split("detection on")[-1].split(":", 1)[-1].strip()[:160]))
            sys.stdout.flush()
        errors.sort()
        print("%s: %d frames, right %d, WRONG %d (median error %s m), %s" % (
            name, a.frames, counts["right"], counts["WRONG"],
            "%.2f" % errors[len(errors) // 2] if errors else "-",
            ", ".join("%s %d" % kv for kv in sorted(counts.items()) if kv[0] not in ("right", "WRONG"))))
        grand.update(counts)
    print("total: right %d, WRONG %d" % (grand["right"], grand["WRONG"]))


if __name__ == "__main__":
    main()
