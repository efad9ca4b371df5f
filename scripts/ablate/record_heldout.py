#!/usr/bin/env python3
"""Records the ablation's held-out closed-loop runs (scripts/ablate/heldout.yaml, `campaign`): make
campaign's scenario generator at fresh seeds, each run's bag kept with its camera images (JPEG, as
record.launch) and the simulator's truth, so that make ablate can replay it losslessly under each rule
switched off. Writes results/ablate/heldout/ (campaign summary, runs/run_NNN/run.bag).

    scripts/ablate/record_heldout.py [--runs N] [--real-time-factor F]
"""
import argparse
import pathlib
import subprocess
import sys

import yaml

ROOT = pathlib.Path(__file__).resolve().parents[2]


def main():
    heldout = yaml.safe_load((ROOT / "scripts" / "ablate" / "heldout.yaml").read_text())["campaign"]
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--runs", type=int, default=heldout["runs"])
    ap.add_argument("--real-time-factor", type=float, default=0.5)
    ap.add_argument("--out", default=str(ROOT / "results" / "ablate" / "heldout"))
    a = ap.parse_args()
    cmd = [sys.executable, str(ROOT / "scripts" / "demo" / "run_campaign.py"), "--runs", str(a.runs),
           "--seed", str(heldout["first_seed"]), "--real-time-factor", str(a.real_time_factor), "--out", a.out,
           "--keep-bags", "--launch-arg", "bag_images:=compressed",
           "--launch-arg", "camera_rate_hz:=%s" % heldout["camera_rate_hz"]]
    sys.exit(subprocess.run(cmd).returncode)


if __name__ == "__main__":
    main()
