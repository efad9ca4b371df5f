#!/usr/bin/env python3
"""What a position-sigma limit would do to a campaign's estimates, counted from its runs' estimates.json
(scripts/demo/run_demo.py writes one per run): per source and per limit (largest position sigma / range),
how many valid estimates it would withhold, how many of those were wrong (off by more than 5 % of the
range or 10 deg, eval_recorder's rule), and how many wrong ones it would leave. The sigma is the largest
diagonal position sigma of the published covariance (the estimator's own check uses the block's largest
eigenvalue, which is at least that), so a count here is a lower bound of what the check withholds.

    sigma_limit_recount.py CAMPAIGN_DIR [CAMPAIGN_DIR ...] [--limits 0.01,0.0167,0.02,0.03]
"""
import argparse
import json
import pathlib
import sys

sys.path.insert(0, str(pathlib.Path(__file__).resolve().parents[1] / "eval"))
from eval_recorder import WRONG_ORIENTATION_DEG, WRONG_POSITION_FRACTION_OF_RANGE  # noqa: E402


def rows_of(campaign_dirs):
    """(run name, source, row) for every estimate of every run that kept its estimates.json."""
    for directory in campaign_dirs:
        for path in sorted(pathlib.Path(directory).glob("runs/run_*/estimates.json")):
            run = f"{pathlib.Path(directory).name}/{path.parent.name}"
            for source, rows in json.loads(path.read_text()).items():
                for row in rows:
                    yield run, source, row


def judged(row):
    """(sigma fraction of range, wrong, range band) of a valid estimate paired with the truth; None otherwise."""
    if row.get("position_error") is None or not row.get("true_range"):
        return None
    sigmas = [s for s in (row.get("sigma") or [])[:3] if s is not None]
    if not sigmas:
        return None
    rng = row["true_range"]
    wrong = row["position_error"] > WRONG_POSITION_FRACTION_OF_RANGE * rng or \
        (row.get("orientation_error") is not None and row["orientation_error"] > WRONG_ORIENTATION_DEG)
    return max(sigmas) / rng, wrong, "< 2 m" if rng < 2.0 else ">= 2 m"


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("campaigns", nargs="+")
    ap.add_argument("--limits", default="0.01,0.0167,0.02,0.03")
    a = ap.parse_args()
    limits = [float(x) for x in a.limits.split(",")]
    table = {}  # (source, band) -> list of (fraction, wrong, run)
    for run, source, row in rows_of(a.campaigns):
        j = judged(row)
        if j is not None:
            table.setdefault((source, j[2]), []).append((j[0], j[1], run))
    if not table:
        print("no estimates.json with judged estimates under", a.campaigns, file=sys.stderr)
        return 1
    print("source        band     valid  wrong | per limit: withheld (of them wrong), wrong left")
    for (source, band), samples in sorted(table.items()):
        wrong = sum(w for _, w, _ in samples)
        cells = []
        for limit in limits:
            held = [(f, w) for f, w, _ in samples if f > limit]
            held_wrong = sum(w for _, w in held)
            cells.append(f"{100 * limit:.2f}%: {len(held)} ({held_wrong}), {wrong - held_wrong}")
        print(f"{source:13s} {band:7s} {len(samples):6d} {wrong:6d} | " + " | ".join(cells))
    print("\nwrong estimates: run, source, sigma/range")
    for (source, band), samples in sorted(table.items()):
        for f, w, run in samples:
            if w:
                print(f"  {run} {source} {band} {100 * f:.2f}%")
    return 0


if __name__ == "__main__":
    sys.exit(main())
