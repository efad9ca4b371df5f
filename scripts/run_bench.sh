#!/usr/bin/env bash
# make bench: single-thread benchmarks of each perception stage on fixed 640x480 frames. Each program
# prints its figures and writes its stages; then scripts/bench_instructions.py counts each stage's
# instructions per frame under callgrind (load-independent). This merges them into results/bench/summary.json:
#   {"image": "640x480", "threads": 1, "stages": {NAME: {"ms_median": float, "hz": float,
#                                                        "instructions_per_frame_M": float}}}
set -euo pipefail
cd "$(dirname "$0")/.."
out=results/bench
mkdir -p "$out/parts"
rm -f "$out"/parts/*.json
lib=devel/lib/docking_perception
status=0
# Fixed rendered frames: the simulator's stereo pair with the target 3 m ahead (raw, distorted images,
# so the disparity stage includes rectification as on the robot).
mkdir -p "$out/frames"
devel/lib/docking_sim/sim_render --config config --scenario eval_far_3m_on --time 1.0 --out "$out/frames/far3m" >/dev/null
echo "== bench_disparity (rectify + disparity + detection on the rendered pair: full resolution, acquiring)"
"$lib/bench_disparity" "$out/parts/disparity.json" --config-dir config \
  --left "$out/frames/far3m_stereo_left.png" --right "$out/frames/far3m_stereo_right.png" || status=1
echo "== bench_disparity --window (full resolution on the tracking window, config/far_stereo.yaml window_*: window_*)"
"$lib/bench_disparity" "$out/parts/disparity_window.json" --config-dir config --window \
  --left "$out/frames/far3m_stereo_left.png" --right "$out/frames/far3m_stereo_right.png" || status=1
echo "== bench_mono (detection + pose, full frame and tracking)"
"$lib/bench_mono" "$out/parts/mono.json" config/target.yaml || status=1
if [ -x "$lib/bench_apriltag" ]; then
  echo "== bench_apriltag (AprilTag 3 and our mono pose on the same frame)"
  # Our target with a tag inset in its face (config/target_tagged_inset.yaml) 1 m ahead, the left
  # camera's frame rectified as mono_pose sees it: AprilTag and our pose on identical pixels.
  devel/lib/docking_sim/sim_render --config config --scenario eval_near_1m_on --time 1.0 --sequence 1 \
    --target config/target_tagged_inset.yaml --out "$out/frames/inset1m" >/dev/null
  "$lib/bench_apriltag" "$out/parts/apriltag.json" --sequence "$out/frames/inset1m" \
    --target config/target_tagged_inset.yaml --mono-params config/mono_pose_visible.yaml || status=1
fi
echo "== bench_instructions (instructions per frame of each stage, callgrind; ~3 min)"
/usr/bin/python3 scripts/bench_instructions.py "$out/parts/instructions.json" \
  --far-left "$out/frames/far3m_stereo_left.png" --far-right "$out/frames/far3m_stereo_right.png" \
  --tagged-sequence "$out/frames/inset1m" --tagged-target config/target_tagged_inset.yaml || status=1
/usr/bin/python3 - "$out" <<'PY'
import json, pathlib, sys
out = pathlib.Path(sys.argv[1])
stages = {}
for part in sorted((out / "parts").glob("*.json")):
    for name, figures in json.loads(part.read_text()).get("stages", {}).items():
        stages.setdefault(name, {}).update(figures)
summary = {"image": "640x480", "threads": 1, "stages": stages}
(out / "summary.json").write_text(json.dumps(summary, indent=2))
print(f"bench: {len(stages)} stages -> {out / 'summary.json'}")
print(f"  {'stage':24s} {'ms CPU':>8s}  {'Hz':>8s}  {'M instr/frame':>13s}")
for name, v in stages.items():
    ms = f"{v['ms_median']:8.2f}" if "ms_median" in v else f"{'-':>8s}"
    hz = f"{v['hz']:8.1f}" if "hz" in v else f"{'-':>8s}"
    instructions = v.get("instructions_per_frame_M")
    print(f"  {name:24s} {ms}  {hz}  {instructions if instructions is not None else '-':>13}")
PY
# What was measured, when, on which commit (docs/PERFORMANCE.md names it: make report).
/usr/bin/python3 scripts/report/provenance.py "$out" "make bench"
exit $status
