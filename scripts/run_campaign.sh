#!/usr/bin/env bash
# make campaign: CAMPAIGN_RUNS (default 50) seeded closed-loop docking runs from randomized starts
# (range, bearing, port angle, rotation rate, lighting) -> results/campaign/summary.json, errors.png.
#   scripts/run_campaign.sh [--runs N] [--seed S] [--timeout SIM_S] ...   (--help)
set -euo pipefail
cd "$(dirname "$0")/.."
export PATH=/usr/bin:$PATH
/usr/bin/python3 scripts/demo/run_campaign.py "$@" ${CAMPAIGN_ARGS:-}
# What was measured, when, on which commit (docs/PERFORMANCE.md names it: make report).
args="$* ${CAMPAIGN_ARGS:-}"; args="${args## }"; args="${args%% }"
runs="${CAMPAIGN_RUNS:+CAMPAIGN_RUNS=$CAMPAIGN_RUNS }"
/usr/bin/python3 scripts/report/provenance.py results/campaign "make campaign ${runs}${args:+CAMPAIGN_ARGS=\"$args\"}"
