#!/usr/bin/env python3
"""make ablate: what each rule of perception and guidance is worth, measured with it switched off on data
it was not chosen on (scripts/ablate/heldout.yaml), one table: rule | suite | detection | confidently wrong |
3-sigma coverage | docking | CPU, against the shipped configuration.

    scripts/ablate/ablate.py [--rules a,b] [--suites replay,stress,campaign] [--out DIR] [--baseline DIR]

Rules: scripts/ablate/rules/*.yaml (each: rule, node, guards, off_by: {key: value}, motivated_by, suite).
"off_by" adds the keys to the node's shipped YAML (every file its settings declaration claims, or the rule's
`files`) in a copy of config/. Suites:
  replay   each held-out run (results/ablate/heldout, scripts/ablate/record_heldout.py) replayed losslessly
           (scripts/tune/tune_replay.replay) and judged against its recorded truth per source;
  stress   the mono stress harness on its report seeds (src/docking_perception: stress_mono);
  campaign closed-loop dockings at the held-out campaign seeds (make campaign's generator).
Writes OUT/table.json and OUT/table.md (default results/ablate/<date-time>/); --baseline reuses the
baseline of an earlier run's folder; a rule already measured in OUT (runs/<rule>/result.json) is not measured
again, so an interrupted run resumes with the same --out.
"""
import argparse
import datetime
import json
import pathlib
import shutil
import subprocess
import sys

import yaml

ROOT = pathlib.Path(__file__).resolve().parents[2]
HERE = pathlib.Path(__file__).resolve().parent
sys.path.insert(0, str(HERE))
sys.path.insert(0, str(ROOT / "scripts" / "tune"))
sys.path.insert(0, str(ROOT / "src" / "docking_settings" / "src"))
import quality  # noqa: E402
from yaml_line_edit import set_key  # noqa: E402
sys.path.insert(0, str(ROOT / "scripts" / "report"))
from provenance import provenance  # noqa: E402
from docking_settings.declarations import find_declarations  # noqa: E402

SUITES = ("replay", "stress", "campaign")


def load_rules():
    rules = []
    for path in sorted((HERE / "rules").glob("*.yaml")):
        for entry in yaml.safe_load(path.read_text()) or []:
            entry["file"] = str(path.relative_to(ROOT))
            rules.append(entry)
    return rules


def node_files(rule):
    """The shipped YAML files the rule edits (its node's settings declaration's `config`, or the rule's
    `files`) and that declaration (None for a node of another package, e.g. stereo_image_proc, whose file's
    existing keys are edited as they are)."""
    for declaration in find_declarations(ROOT):
        if declaration.node == rule["node"]:
            return rule.get("files", [pathlib.Path(c).name for c in declaration.config]), declaration
    if "files" not in rule:
        raise SystemExit("ablate: %s: no settings declaration for node %s, and no `files`" % (rule["rule"], rule["node"]))
    return rule["files"], None


def make_config(rule, folder):
    """config/ copied to `folder`, with the rule's settings switched off (no rule: the shipped one)."""
    shutil.rmtree(folder, ignore_errors=True)
    shutil.copytree(ROOT / "config", folder)
    if rule is None:
        return folder
    files, declaration = node_files(rule)
    for key, value in rule["off_by"].items():
        if declaration is not None and key not in declaration.settings:
            raise SystemExit("ablate: %s: %s is not a setting of %s" % (rule["rule"], key, rule["node"]))
        problem = declaration.settings[key].problem(value) if declaration is not None else None
        if problem:
            raise SystemExit("ablate: %s: %s: %s" % (rule["rule"], key, problem))
        for name in files:
            set_key(str(folder / name), key, json.dumps(value))
    return folder


def heldout_bags():
    bags = sorted((ROOT / "results" / "ablate" / "heldout" / "runs").glob("run_*/run.bag"))
    if not bags:
        raise SystemExit("ablate: no held-out runs in results/ablate/heldout: record them with "
                         "scripts/ablate/record_heldout.py (about 2 min per run)")
    return bags


def run_replay(config_dir, work):
    import tune_replay
    per_bag = []
    for bag in heldout_bags():
        out_bag = work / (bag.parent.name + ".bag")
        tune_replay.replay(bag, config_dir, out_bag, work / (bag.parent.name + ".log"), timeout_s=3600.0)
        per_bag.append(quality.replay_quality(bag, out_bag))
        out_bag.unlink()
    return quality.pooled(per_bag)


def run_stress(config_dir, work):
    heldout = yaml.safe_load((HERE / "heldout.yaml").read_text())["stress"]
    out = work / "stress.json"
    cmd = [str(ROOT / "devel" / "lib" / "docking_perception" / "stress_mono"), "--target", str(config_dir / "target.yaml"),
           "--visible", str(config_dir / "mono_pose_visible.yaml"), "--ir", str(config_dir / "mono_pose_ir.yaml"),
           "--seeds", heldout["seeds"], "--frames", str(heldout["frames"]), "--out", str(out)]
    done = subprocess.run(cmd, capture_output=True, text=True)
    if done.returncode != 0:
        raise RuntimeError("stress_mono failed: %s" % done.stderr[-2000:])
    return summarize_stress(json.loads(out.read_text()))


def summarize_stress(report):
    """Pooled over the harness's conditions (visible and IR apart): detection, confidently wrong, the lowest
    3-sigma share of a condition with estimates, CPU (mean of the conditions' medians)."""
    out = {}
    for source, infrared in (("stress_visible", False), ("stress_ir", True)):
        rows = [r for name, r in report["conditions"].items() if name.startswith("ir_") == infrared]
        frames = sum(r["frames"] for r in rows)
        valid = sum(r["valid"] for r in rows)
        coverage = [min(r["coverage_3sigma"]) for r in rows if r["valid"] > 0]
        cpu = [r["cpu_ms_median"] for r in rows]
        out[source] = {"frames": frames, "valid": valid, "detection": valid / frames if frames else None,
                       "confident_wrong": sum(r["confident_wrong"] for r in rows),
                       "lowest_3_sigma": min(coverage) if coverage else None,
                       "cpu_ms": sum(cpu) / len(cpu) if cpu else None}
    return out


def run_campaign(config_dir, work):
    heldout = yaml.safe_load((HERE / "heldout.yaml").read_text())["campaign"]
    cmd = [sys.executable, str(ROOT / "scripts" / "demo" / "run_campaign.py"), "--runs", str(heldout["runs"]),
           "--seed", str(heldout["first_seed"]), "--out", str(work / "campaign"),
           "--launch-arg", "config_dir:=%s" % config_dir]
    subprocess.run(cmd, check=True, stdout=subprocess.DEVNULL)
    summary = json.loads((work / "campaign" / "summary.json").read_text())
    return {"docking": {"success_rate": summary["success_rate"], "tip_p95_mm": summary["position_error_mm"]["p95"]}}


RUNNERS = {"replay": run_replay, "stress": run_stress, "campaign": run_campaign}


def measure(rule, suites, out):
    label = rule["rule"] if rule else "baseline"
    work = out / "runs" / label
    work.mkdir(parents=True, exist_ok=True)
    done = json.loads((work / "result.json").read_text()) if (work / "result.json").exists() else {}
    if all(suite in done for suite in suites):
        print("ablate: %s: measured before in %s" % (label, work), flush=True)
        return {suite: done[suite] for suite in suites}
    config_dir = make_config(rule, work / "config")
    results = {}
    for suite in suites:
        print("ablate: %s: %s ..." % (label, suite), flush=True)
        results[suite] = RUNNERS[suite](config_dir, work)
    (work / "result.json").write_text(json.dumps(results, indent=1))
    return results


def delta(value, base, scale=1.0, digits=2):
    if value is None or base is None:
        return "-"
    return ("%+." + str(digits) + "f") % ((value - base) * scale)


def table_rows(rules, results, baseline):
    lines = ["| rule | guards | suite | source | detection off (Δ pp) | confidently wrong off / on | lowest 3σ off / on | "
             "docking off / on | CPU ms off (Δ) |", "|---|---|---|---|---|---|---|---|---|"]
    for rule in rules:
        for suite, by_source in results[rule["rule"]].items():
            for source, m in by_source.items():
                b = baseline[suite][source]
                if suite == "campaign":
                    lines.append("| `%s` | %s | campaign | - | - | - | - | %.2f / %.2f | - |" % (
                        rule["rule"], rule["guards"], m["success_rate"], b["success_rate"]))
                    continue
                lines.append("| `%s` | %s | %s | %s | %s (%s) | %s / %s | %s / %s | - | %s (%s) |" % (
                    rule["rule"], rule["guards"], suite, source,
                    "-" if m["detection"] is None else "%.3f" % m["detection"], delta(m["detection"], b["detection"], 100.0, 1),
                    m["confident_wrong"], b["confident_wrong"],
                    "-" if m["lowest_3_sigma"] is None else "%.2f" % m["lowest_3_sigma"],
                    "-" if b["lowest_3_sigma"] is None else "%.2f" % b["lowest_3_sigma"],
                    "-" if m["cpu_ms"] is None else "%.1f" % m["cpu_ms"], delta(m["cpu_ms"], b["cpu_ms"], 1.0, 1)))
    return lines


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--rules", help="comma-separated rule names (default: all)")
    ap.add_argument("--suites", help="comma-separated suites (default: each rule's own)")
    ap.add_argument("--out", help="output folder (default results/ablate/<date-time>)")
    ap.add_argument("--baseline", help="an earlier output folder whose baseline to reuse")
    a = ap.parse_args()
    rules = load_rules()
    if a.rules:
        wanted = set(a.rules.split(","))
        rules = [r for r in rules if r["rule"] in wanted]
    out = pathlib.Path(a.out or ROOT / "results" / "ablate" / datetime.datetime.now().strftime("%Y%m%d-%H%M%S")).resolve()
    out.mkdir(parents=True, exist_ok=True)
    suites_of = {r["rule"]: (a.suites.split(",") if a.suites else [r["suite"]]) for r in rules}
    needed = sorted({s for ss in suites_of.values() for s in ss}, key=SUITES.index)
    baseline_file = pathlib.Path(a.baseline) / "runs" / "baseline" / "result.json" if a.baseline else None
    baseline = json.loads(baseline_file.read_text()) if baseline_file else {}
    missing = [s for s in needed if s not in baseline]
    if missing:
        baseline.update(measure(None, missing, out))
    results = {r["rule"]: measure(r, suites_of[r["rule"]], out) for r in rules}
    (out / "table.json").write_text(json.dumps({"baseline": baseline, "rules": rules, "results": results}, indent=1))
    text = "\n".join(table_rows(rules, results, baseline)) + "\n"
    (out / "table.md").write_text(text)
    command = "make ablate" + (' ABLATE_ARGS="%s"' % " ".join(sys.argv[1:]) if sys.argv[1:] else "")
    (out / "provenance.json").write_text(json.dumps(provenance(command), indent=2) + "\n")
    print(text)


if __name__ == "__main__":
    main()
