#!/usr/bin/env python3
"""Writes the tables that README.md, docs/TUNING.md and bags/README.md print from the tuning tool, by running
the tool, so that what a doc shows is what the tool prints today (issue 54); --check compares instead.

  scripts/tune/doc_tables.py            # runs the example sweeps, rewrites the generated blocks of the docs
  scripts/tune/doc_tables.py --check    # runs them, exits 1 with a diff when a doc's block differs

Each example is a `make tune` sweep on a sample bag of bags/ (scripts/tune/tune_replay.py, lossless
replays: the same estimates every run); its table is the tool's own (table.txt). bags/README.md's figures
come from the same replays: per bag, the sweep's run at the value config/ holds. A doc's generated block
sits between the lines `<!-- doc_tables.py: NAME -->` and `<!-- end doc_tables.py: NAME -->`.
The CPU column (cpu ms) is measured, not computed: it changes from run to run and --check ignores it.
The replays' reports stay in --out (default results/doc_tables/): the doc_tables rostest holds them to limits.
Six replays of 30 frames, the two sweeps side by side: ~2-3 min on the 2-core machine.
"""
import argparse
import dataclasses
import difflib
import json
import pathlib
import re
import subprocess
import sys

ROOT = pathlib.Path(__file__).resolve().parents[2]
TUNE = ROOT / "scripts" / "tune" / "tune_replay.py"


@dataclasses.dataclass
class Sweep:
    name: str     # the generated block's name in its doc, and the output folder's
    bag: str      # relative to the repository
    sweep: str    # FILE.yaml:KEY=V1,V2,V3, one of them config/'s own value
    doc: str      # the doc that prints its table


SWEEPS = (
    Sweep("far_sweep", "bags/far_approach.bag", "disparity_detector.yaml:median_kernel_px=0,3,5", "README.md"),
    Sweep("near_sweep", "bags/near_approach.bag", "mono_pose_visible.yaml:fast_threshold=5,10,20", "docs/TUNING.md"),
)
BAG_FIGURES = ("bags/README.md", "sample_bag_figures")
# bags/README.md's rows: (bag's sweep, source, label)
BAG_ROWS = (("far_sweep", "disparity", "disparity"), ("far_sweep", "fused", "`/target/estimate` (fused)"),
            ("near_sweep", "mono_visible", "mono visible"), ("near_sweep", "mono_ir", "mono IR"),
            ("near_sweep", "fused", "`/target/estimate` (fused)"))
CPU_CELL = re.compile(r"(\d+\.\d / \d+\.\d|-)$")  # a table row's last cell: cpu ms median / p95


def run_sweeps(out):
    """Each sweep as `make tune` runs it, the two side by side (lossless replays give the same estimates
    whatever the load); returns per sweep its report (report.json) and printed table (table.txt)."""
    runs = {}
    for sweep in SWEEPS:
        cmd = [sys.executable, str(TUNE), "--bag", str(ROOT / sweep.bag), "--sweep", sweep.sweep,
               "--out", str(out / sweep.name)]
        runs[sweep.name] = (cmd, subprocess.Popen(cmd, stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True))
    results = {}
    for name, (cmd, proc) in runs.items():
        printed = proc.communicate()[0]
        if proc.returncode != 0:
            sys.exit("doc_tables: %s failed:\n%s" % (" ".join(cmd), printed[-3000:]))
        folder = out / name
        results[name] = (json.loads((folder / "report.json").read_text()),
                         (folder / "table.txt").read_text().rstrip("\n"))
    return results


def sweep_block(sweep, table):
    return "```\n$ make tune BAG=$PWD/%s SWEEP=\"%s\"\n%s\n```" % (sweep.bag, sweep.sweep, table)


def config_run(report):
    """The configuration of a sweep whose value is the one config/ holds (its edit replaced an equal value)."""
    for configuration in report["configurations"]:
        edit = configuration["edits"][-1]
        if str(configuration["replaced_values"][edit]) == edit.rsplit("=", 1)[1]:
            return configuration
    sys.exit("doc_tables: no value of the sweep is config/'s own (%s)" % report["configurations"][0]["edits"])


def figures_block(reports):
    rows = ["| bag | estimate | valid frames | position error median / p95 | orientation error median |",
            "|---|---|---|---|---|"]
    for sweep_name, source, label in BAG_ROWS:
        bag = next(s.bag for s in SWEEPS if s.name == sweep_name)
        m = config_run(reports[sweep_name])["sources"][source]
        position, orientation = m["position_error_mm"], m["orientation_error_deg"]
        rows.append("| %s | %s | %d / %d | %.1f / %.1f mm | %s |" % (
            pathlib.Path(bag).stem, label, m["valid_frames"], m["frames"], position["median"], position["p95"],
            "(position only)" if not orientation or orientation.get("median") is None else "%.2f°" % orientation["median"]))
    return "\n".join(rows)


def markers(name):
    return "<!-- doc_tables.py: %s -->" % name, "<!-- end doc_tables.py: %s -->" % name


def block_of(text, name, doc):
    start, end = markers(name)
    if start not in text or end not in text:
        sys.exit("doc_tables: %s has no block %s (lines %r and %r)" % (doc, name, start, end))
    return text.split(start, 1)[1].split(end, 1)[0].strip("\n")


def without_cpu(block):
    """The block with each table row's CPU cell masked: measured, it changes from run to run."""
    return [CPU_CELL.sub("*", line) if re.match(r"^(disparity|mono_visible|mono_ir|fused) ", line) else line
            for line in block.splitlines()]


def main():
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--check", action="store_true", help="compare with the docs instead of rewriting them")
    parser.add_argument("--out", default=str(ROOT / "results" / "doc_tables"), help="where the replays go")
    args = parser.parse_args()
    out = pathlib.Path(args.out)
    reports, blocks = {}, {}
    results = run_sweeps(out)
    for sweep in SWEEPS:
        reports[sweep.name], table = results[sweep.name]
        blocks[(sweep.doc, sweep.name)] = sweep_block(sweep, table)
    blocks[BAG_FIGURES] = figures_block(reports)
    differences = []
    for (doc, name), block in blocks.items():
        path = ROOT / doc
        text = path.read_text()
        current = block_of(text, name, doc)
        if args.check:
            if without_cpu(current) != without_cpu(block):
                differences += ["%s, block %s:" % (doc, name)] + list(difflib.unified_diff(
                    without_cpu(current), without_cpu(block), "in the doc", "printed today", lineterm=""))
            continue
        start, end = markers(name)
        before, rest = text.split(start, 1)
        after = rest.split(end, 1)[1]
        path.write_text(before + start + "\n" + block + "\n" + end + after)
        print("doc_tables: %s: block %s written" % (doc, name))
    if differences:
        print("\n".join(differences))
        print("doc_tables: the docs differ from what the tool prints today: run scripts/tune/doc_tables.py")
        return 1
    if args.check:
        print("doc_tables: every generated block matches what the tool prints today (CPU cells aside)")
    return 0


if __name__ == "__main__":
    sys.exit(main())
