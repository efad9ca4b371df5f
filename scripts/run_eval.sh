#!/usr/bin/env bash
# make eval: perception against simulator ground truth (scripts/eval/run_eval.py --help).
set -euo pipefail
cd "$(dirname "$0")/.."
exec /usr/bin/python3 scripts/eval/run_eval.py "$@" ${EVAL_ARGS:-}
