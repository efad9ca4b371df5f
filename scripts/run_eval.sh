#!/usr/bin/env bash
# make eval: perception against simulator ground truth.
#  1. scripts/eval/run_eval.py (--help): every source in the running stack, scenario by scenario
#     -> results/eval/summary.json and plots;
#  2. scripts/eval/mono_comparison.py: the two pose solvers, the two velocity methods and AprilTag 3
#     on the same rendered frames, offline -> results/eval/mono_comparison.json.
# EVAL_ARGS are passed to run_eval.py (e.g. EVAL_ARGS="--set near").
set -euo pipefail
cd "$(dirname "$0")/.."
/usr/bin/python3 scripts/eval/run_eval.py "$@" ${EVAL_ARGS:-}
/usr/bin/python3 scripts/eval/mono_comparison.py --out results/eval/mono_comparison.json
# What was measured, when, on which commit (docs/PERFORMANCE.md names it: make report).
args="$* ${EVAL_ARGS:-}"; args="${args## }"; args="${args%% }"
/usr/bin/python3 scripts/report/provenance.py results/eval "make eval${args:+ EVAL_ARGS=\"$args\"}"
