#!/usr/bin/env python3
"""Prints a Markdown table of a `make eval` summary (results/eval/summary.json): per scenario and source,
detection rate, median position error (% of range), median orientation error, the worst per-axis share
of errors within 3 sigma, and the confident-wrong count (valid, off by > 5 % of range or > 10 deg).

  summary_table.py SUMMARY.json [--sources mono_visible mono_ir disparity fused]
"""
import argparse
import json


def cell(entry):
    if entry is None:
        return "-"
    det = entry["detection_rate"]
    if not entry.get("position_error_median_m") and det == 0.0:
        return f"{det:.2f}"
    rng = entry.get("range_error_median_pct")
    ori = entry.get("orientation_error_median_deg")
    shares = [s for s in (entry.get("within_3_sigma") or {}).values() if s is not None]
    text = f"{det:.2f}"
    if rng is not None:
        text += f", {rng:.2f} %"
    if ori is not None:
        text += f", {ori:.2f} deg"
    if shares:
        text += f", 3σ {min(shares):.2f}"
    wrong = entry.get("confident_wrong", 0)
    if wrong:
        text += f", **{wrong} wrong**"
    return text


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("summary")
    ap.add_argument("--sources", nargs="*", default=["mono_visible", "mono_ir", "disparity", "fused"])
    a = ap.parse_args()
    scenarios = json.load(open(a.summary))["scenarios"]
    print("| scenario | " + " | ".join(a.sources) + " |")
    print("|---" * (len(a.sources) + 1) + "|")
    for s in scenarios:
        print(f"| {s['name']} | " + " | ".join(cell(s["sources"].get(src)) for src in a.sources) + " |")


if __name__ == "__main__":
    main()
