#!/usr/bin/env bash
# make bench: single-thread benchmarks of each perception stage on fixed 640x480 frames. Each program
# prints its figures and writes its stages; this merges them into results/bench/summary.json:
#   {"image": "640x480", "threads": 1, "stages": {NAME: {"ms_median": float, "hz": float}}}
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
echo "== bench_disparity (rectify + disparity + detection on the rendered pair)"
"$lib/bench_disparity" "$out/parts/disparity.json" --config-dir config \
  --left "$out/frames/far3m_stereo_left.png" --right "$out/frames/far3m_stereo_right.png" || status=1
echo "== bench_mono (detection + pose, full frame and tracking)"
"$lib/bench_mono" "$out/parts/mono.json" config/target.yaml || status=1
if [ -x "$lib/bench_apriltag" ]; then
  echo "== bench_apriltag (AprilTag 3 on the tagged target variant)"
  # The tagged target (config/target_tagged.yaml) 1 m ahead, left camera rectified as mono_pose sees it.
  devel/lib/docking_sim/sim_render --config config --scenario eval_near_1m_on --time 1.0 --sequence 1 \
    --target config/target_tagged.yaml --out "$out/frames/tagged1m" >/dev/null
  "$lib/bench_apriltag" "$out/parts/apriltag.json" --sequence "$out/frames/tagged1m" \
    --target config/target_tagged.yaml || status=1
fi
/usr/bin/python3 - "$out" <<'PY'
import json, pathlib, sys
out = pathlib.Path(sys.argv[1])
stages = {}
for part in sorted((out / "parts").glob("*.json")):
    stages.update(json.loads(part.read_text()).get("stages", {}))
summary = {"image": "640x480", "threads": 1, "stages": stages}
(out / "summary.json").write_text(json.dumps(summary, indent=2))
print(f"bench: {len(stages)} stages -> {out / 'summary.json'}")
for name, v in stages.items():
    print(f"  {name:24s} {v['ms_median']:8.2f} ms  {v['hz']:8.1f} Hz")
PY
exit $status
