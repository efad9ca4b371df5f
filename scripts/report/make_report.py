#!/usr/bin/env python3
"""make report: docs/PERFORMANCE.md, the current figures, generated.

Two steps, so that the page can be checked on a clean clone (results/ is never committed):
  1. collect: the results under RESULTS (make eval, make bench, make campaign, make demo, make ablate; each
     folder's provenance.json names the command, date and commit) are merged into FIGURES
     (docs/performance-figures.json, committed). A row measured again replaces the old one; a row not
     measured again keeps its own date, commit and command.
  2. render: FIGURES (and the ablation rules of scripts/ablate/rules/*.yaml) -> the Markdown page.

    make_report.py [--results DIR] [--figures FILE] [--out FILE]   collect, then render (make report)
    make_report.py --render-only [--figures FILE] [--out FILE|-]   render FIGURES as they are
    make_report.py --check [--figures FILE] [--out FILE]           exit 1 unless FILE is what FIGURES renders
"""
import argparse
import datetime
import json
import pathlib
import sys

import yaml

ROOT = pathlib.Path(__file__).resolve().parents[2]
sys.path.insert(0, str(pathlib.Path(__file__).resolve().parent))
import render  # noqa: E402

SOURCES = ("disparity", "mono_visible", "mono_ir", "fused")
EVAL_KEYS = ("frames", "detection_rate", "position_error_median_m", "position_error_p95_m", "range_error_median_pct",
             "orientation_error_median_deg", "orientation_error_p95_deg", "linear_velocity_error_median_mps",
             "angular_velocity_error_median_dps", "rate_hz", "processing_ms_median", "confident_wrong")


def load_json(path):
    return json.loads(path.read_text()) if path.is_file() else None


def provenance_of(folder, result_file, default_command):
    """The result's own "provenance", the folder's provenance.json, or (measured without either) the result
    file's date and an unknown commit."""
    found = (load_json(result_file) or {}).get("provenance") or load_json(folder / "provenance.json")
    if found:
        return {k: found[k] for k in ("command", "commit", "date")}
    mtime = datetime.datetime.fromtimestamp(result_file.stat().st_mtime, datetime.timezone.utc)
    return {"command": default_command, "commit": "unknown", "date": mtime.strftime("%Y-%m-%d %H:%M UTC")}


def lowest_share(within):
    shares = [v for v in (within or {}).values() if v is not None]
    return min(shares) if shares else None


def collect_eval(results, figures):
    folder = results / "eval"
    summary = load_json(folder / "summary.json")
    if summary is None:
        return {}
    measured = provenance_of(folder, folder / "summary.json", "make eval")
    scenarios = figures.setdefault("eval", {})
    for scenario in summary["scenarios"]:
        sources = {}
        for name, entry in scenario["sources"].items():
            kept = {k: entry.get(k) for k in EVAL_KEYS}
            kept["lowest_3_sigma"] = lowest_share(entry.get("within_3_sigma"))
            sources[name] = kept
        scenarios[scenario["name"]] = {"range_m": scenario["range_m"], "lighting": scenario["lighting"],
                                       "sources": sources, "measured": measured}
    return {"results/eval/summary.json": measured}


def collect_mono_comparison(results, figures):
    folder = results / "eval"
    summary = load_json(folder / "mono_comparison.json")
    if summary is None:
        return {}
    measured = provenance_of(folder, folder / "mono_comparison.json", "make eval")
    table = figures.setdefault("mono_comparison", {})
    for name, scenario in summary["scenarios"].items():
        methods = {}
        for method, m in scenario["methods"].items():
            methods[method] = {"detection_rate": m["detection_rate"],
                               "position_error_median_m": m["position_error_m"]["median"],
                               "orientation_error_median_deg": m["orientation_error_deg"]["median"],
                               "ms_median": m["ms_per_frame"]["median"],
                               "velocity_filter": (m.get("velocity") or {}).get("filter"),
                               "velocity_frame_difference": (m.get("velocity") or {}).get("frame_difference")}
        table[name] = {"range_m": scenario["range_m"], "face_off_axis_deg": scenario["face_off_axis_deg"],
                       "methods": methods, "measured": measured}
    return {"results/eval/mono_comparison.json": measured}


def collect_bench(results, figures):
    folder = results / "bench"
    summary = load_json(folder / "summary.json")
    if summary is None:
        return {}
    figures["bench"] = {"stages": summary["stages"], "image": summary.get("image"), "threads": summary.get("threads"),
                        "measured": provenance_of(folder, folder / "summary.json", "make bench")}
    return {"results/bench/summary.json": figures["bench"]["measured"]}


def collect_demo(results, figures):
    folder = results / "demo"
    summary = load_json(folder / "summary.json")
    if summary is None:
        return {}
    latency = summary.get("image_to_cmd_vel_latency_wall") or {}
    figures["demo"] = {
        "docked": summary.get("docked"), "time_to_dock_s": summary.get("time_to_dock_s"),
        "position_error_mm": None if summary.get("final_position_error_m") is None
        else 1000.0 * summary["final_position_error_m"],
        "yaw_error_deg": summary.get("final_yaw_error_deg"),
        "real_time_factor": summary.get("achieved_real_time_factor"),
        "latency": {k: latency.get(k) for k in ("count", "median_ms", "p95_ms", "max_ms", "perception_median_ms",
                                                  "perception_p95_ms", "planner_median_ms", "planner_p95_ms")},
        "measured": provenance_of(folder, folder / "summary.json", "make demo")}
    return {"results/demo/summary.json": figures["demo"]["measured"]}


def collect_campaign(results, figures):
    folder = results / "campaign"
    summary = load_json(folder / "summary.json")
    if summary is None:
        return {}
    keys = ("runs", "seed_range", "success_rate", "docked_rate", "position_error_mm", "yaw_error_deg",
            "time_to_dock_s", "latency_p95_ms", "achieved_real_time_factor", "failure_causes")
    row = {k: summary.get(k) for k in keys}
    row["measured"] = provenance_of(folder, folder / "summary.json", "make campaign")
    campaigns = [c for c in figures.get("campaigns", []) if c["measured"]["command"] != row["measured"]["command"]]
    figures["campaigns"] = [row] + campaigns[:2]   # the newest three campaigns, each a different command
    return {"results/campaign/summary.json": row["measured"]}


def collect_stack(results, figures):
    """scripts/eval/stack_memory.py's result: CPU and memory of the robot's stack in one scenario."""
    result_file = results / "stack_memory.json"
    result = load_json(result_file)
    if result is None:
        return {}
    measured = provenance_of(results, result_file, "scripts/eval/stack_memory.py")
    stack = figures.setdefault("stack", {})
    stack["%s at %g Hz" % (result["scenario"], result["camera_rate_hz"])] = {
        "scenario": result["scenario"], "camera_rate_hz": result["camera_rate_hz"],
        "cpu_cores": result.get("stack_cpu_cores_per_sim_second"),
        "pss_mb": result.get("stack_peak_of_pss_sum_mb"), "rss_mb": result.get("stack_peak_of_sum_mb"),
        "measured": measured}
    return {"results/stack_memory.json": measured}


def collect_ablation(results, figures):
    """Every results/ablate/<date-time>/table.json, oldest first: a rule measured again replaces its row."""
    names = {}
    rules = figures.setdefault("ablation", {})
    for table_file in sorted((results / "ablate").glob("*/table.json")):
        table = json.loads(table_file.read_text())
        measured = provenance_of(table_file.parent, table_file, "make ablate")
        for rule in table["rules"]:
            effects = table["results"].get(rule["rule"])
            if effects:
                rules[rule["rule"]] = {"off": effects, "on": {s: table["baseline"].get(s) for s in effects},
                                       "measured": measured}
        names["results/" + str(table_file.relative_to(results))] = measured
    return names


COLLECTORS = (collect_demo, collect_campaign, collect_eval, collect_mono_comparison, collect_bench, collect_stack,
              collect_ablation)


def referenced(node):
    """Every provenance ("measured") a row of the figures still carries."""
    if isinstance(node, dict):
        found = [node["measured"]] if isinstance(node.get("measured"), dict) else []
        return found + [m for key, value in node.items() if key != "sources" for m in referenced(value)]
    if isinstance(node, list):
        return [m for value in node for m in referenced(value)]
    return []


def collect(results, figures):
    """Merges every result found into figures. figures["sources"]: per result file, the provenances of the
    runs whose rows the page still shows (a file measured again by another command keeps both)."""
    read = {}
    for collector in COLLECTORS:
        read.update(collector(results, figures))
    sources = {name: (runs if isinstance(runs, list) else [runs]) for name, runs in figures.get("sources", {}).items()}
    for name, measured in read.items():
        sources[name] = [m for m in sources.get(name, []) if m["command"] != measured["command"]] + [measured]
    kept = {}
    for name, runs in sources.items():
        in_use = referenced(figures.get(section_of(name)))
        if [m for m in runs if m in in_use]:
            kept[name] = [m for m in runs if m in in_use]
    figures["sources"] = kept
    return sorted(read)


def section_of(result_file):
    """The part of the figures that a result file's rows go to."""
    for part, section in (("mono_comparison", "mono_comparison"), ("eval/", "eval"), ("campaign/", "campaigns"),
                          ("demo/", "demo"), ("bench/", "bench"), ("stack_memory", "stack"), ("ablate/", "ablation")):
        if part in result_file:
            return section
    return None


def ablation_rules():
    rules = []
    for path in sorted((ROOT / "scripts" / "ablate" / "rules").glob("*.yaml")):
        for entry in yaml.safe_load(path.read_text()) or []:
            rules.append({"rule": entry["rule"], "node": entry.get("node", ""), "guards": entry.get("guards", "")})
    return rules


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--results", default=str(ROOT / "results"))
    ap.add_argument("--figures", default=str(ROOT / "docs" / "performance-figures.json"))
    ap.add_argument("--out", default=str(ROOT / "docs" / "PERFORMANCE.md"), help="the page ('-': stdout)")
    mode = ap.add_mutually_exclusive_group()
    mode.add_argument("--render-only", action="store_true")
    mode.add_argument("--check", action="store_true")
    a = ap.parse_args()
    figures_file = pathlib.Path(a.figures)
    figures = load_json(figures_file) or {}
    if not a.render_only and not a.check:
        read = collect(pathlib.Path(a.results), figures)
        figures_file.write_text(json.dumps(figures, indent=1) + "\n")
        print("report: %d result files read (%s) -> %s" % (len(read), ", ".join(read) or "none", figures_file),
              file=sys.stderr)
    page = render.page(figures, ablation_rules())
    if a.check:
        current = pathlib.Path(a.out).read_text() if pathlib.Path(a.out).is_file() else ""
        if current != page:
            print("report: %s is not what %s renders (run make report)" % (a.out, figures_file))
            sys.exit(1)
        print("report: %s is current (%d lines)" % (a.out, page.count("\n")))
        return
    if a.out == "-":
        sys.stdout.write(page)
    else:
        pathlib.Path(a.out).write_text(page)
        print("report: %s (%d lines)" % (a.out, page.count("\n")), file=sys.stderr)


if __name__ == "__main__":
    main()
