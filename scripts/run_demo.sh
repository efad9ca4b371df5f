#!/usr/bin/env bash
# make demo: one closed-loop docking in the simulator (default scenario), headless, until DOCKED or a
# 240 s (sim) timeout; summary printed and written to results/demo/ (summary.json, run.bag, PNG plots).
#   scripts/run_demo.sh [--scenario NAME] [--timeout S] [--real-time-factor F] ...   (--help)
# Environment: DEMO_ARGS (extra arguments), DEMO_RTF, DEMO_CAMERA_RATE_HZ.
set -euo pipefail
cd "$(dirname "$0")/.."
export PATH=/usr/bin:$PATH
/usr/bin/python3 scripts/demo/run_demo.py "$@" ${DEMO_ARGS:-}
# What was measured, when, on which commit (docs/PERFORMANCE.md names it: make report).
args="$* ${DEMO_ARGS:-}"; args="${args## }"; args="${args%% }"
/usr/bin/python3 scripts/report/provenance.py results/demo "make demo${args:+ DEMO_ARGS=\"$args\"}"
