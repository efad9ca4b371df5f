#!/usr/bin/env python3
"""How much a still scene's orientation error is the view's own draw (issue 11).

A still eval scene renders one view for its whole duration, so its per-frame errors are one error seen
through sensor noise, and its "median" is a single draw of the per-view error. This renders the same
scene with the port moved a few millimetres along the line of sight (views that differ only in where
the face's texture falls on the pixel grid) and prints compare_mono's orientation error per view and
across views, for PnP on the features and for the paper's five dots. A program that prints figures;
nothing here asserts.

  scripts/eval/static_view_spread.py [--range 1.4] [--turn 10] [--shifts-mm -6,-4,-2,0,2,4,6]
                                     [--visible "{optics: {f_number: 0.0}, blur_sigma_px: 0.0}" | --defocus-px 2]
                                     [--mono-config FILE] [--frames 40] [--seed 24]
                                     [--out results/static_view_spread.json]
--visible: a camera_overrides entry for the visible camera (sim.yaml's keys); --defocus-px: the lens
misfocused so that the port is blurred by this sigma (make_eval_scenarios.defocus_2px, as the
eval_real_defocus2px_* scenes). Neither: sim.yaml's C270.
"""
import argparse
import importlib.util
import json
import pathlib
import shutil
import statistics
import subprocess
import tempfile
from concurrent.futures import ThreadPoolExecutor

ROOT = pathlib.Path(__file__).resolve().parents[2]
RENDER = ROOT / "devel" / "lib" / "docking_sim" / "sim_render"
COMPARE = ROOT / "devel" / "lib" / "docking_perception" / "compare_mono"
METHODS = ("pnp", "paper_5point")


def scenario_writer():
    """make_eval_scenarios (one scene generator), loaded from its file."""
    spec = importlib.util.spec_from_file_location("make_eval_scenarios", ROOT / "scripts/eval/make_eval_scenarios.py")
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


def parse_args():
    p = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument("--range", type=float, default=1.4, help="port range, m")
    p.add_argument("--turn", type=float, default=10.0, help="the port turned away from the camera, deg")
    p.add_argument("--shifts-mm", default="-6,-4,-2,0,2,4,6", help="range offsets of the views, mm")
    group = p.add_mutually_exclusive_group()
    group.add_argument("--visible", default="", help="camera_overrides for the visible camera")
    group.add_argument("--defocus-px", type=float, default=0.0, help="defocus sigma at the port, px")
    p.add_argument("--mono-config", default=str(ROOT / "config/mono_pose_visible.yaml"),
                   help="the visible pose's parameters (a variant to compare)")
    p.add_argument("--frames", type=int, default=40)
    p.add_argument("--seed", type=int, default=24)
    p.add_argument("--out", default="results/static_view_spread.json")
    return p.parse_args()


def write_scenes(args, scenes_dir):
    """One scenario per shifted view; returns [(name, range_m)]."""
    writer = scenario_writer()
    writer.OUT = scenes_dir
    views = []
    for shift in [float(s) for s in args.shifts_mm.split(",")]:
        range_m = args.range + shift * 1e-3
        visible = writer.defocus_2px(range_m, args.defocus_px) if args.defocus_px > 0 else args.visible
        extra = {"camera_overrides": {"visible": visible}} if visible else None
        name = f"spread_{shift:+.1f}mm".replace("+", "p").replace("-", "m").replace(".", "_")
        writer.write(name, f"static view spread probe: {shift:+.1f} mm", range_m, 0.0, args.turn, seed=args.seed,
                     extra=extra)
        views.append((name, range_m))
    return views


def measure(view, config, work, frames, mono_config):
    """Renders a view's sequence and runs compare_mono on it: {method: orientation median, deg}."""
    name, _ = view
    seq = work / f"seq_{name}"
    out = work / f"compare_{name}.json"
    subprocess.run([str(RENDER), "--config", str(config), "--scenario", name, "--sequence", str(frames), "--time",
                    "4", "--out", str(seq)], check=True, capture_output=True)
    subprocess.run([str(COMPARE), "--sequence", str(seq), "--target", str(ROOT / "config/target.yaml"),
                    "--mono-config", mono_config, "--out", str(out)], check=True,
                   capture_output=True)
    methods = json.loads(out.read_text())["methods"]
    result = {}
    for method in METHODS:
        errors = methods[method].get("orientation_error_deg")
        result[method] = errors["median"] if isinstance(errors, dict) else None
    return result


def main():
    args = parse_args()
    with tempfile.TemporaryDirectory(prefix="static_view_spread_") as tmp:
        work = pathlib.Path(tmp)
        config = work / "config"
        shutil.copytree(ROOT / "config", config, ignore=shutil.ignore_patterns("scenarios", "textures"))
        (config / "textures").symlink_to(ROOT / "config" / "textures")
        (config / "scenarios").mkdir()
        views = write_scenes(args, config / "scenarios")
        with ThreadPoolExecutor(max_workers=2) as pool:
            results = list(pool.map(lambda v: measure(v, config, work, args.frames, args.mono_config), views))
    print(f"port {args.range} m, turned {args.turn} deg; orientation error of each view (deg, median of "
          f"{args.frames} frames)")
    print(f"{'range m':>9} " + " ".join(f"{m:>13}" for m in METHODS))
    for (_, range_m), result in zip(views, results):
        print(f"{range_m:9.4f} " + " ".join(f"{result[m]:13.3f}" if result[m] is not None else f"{'-':>13}"
                                            for m in METHODS))
    summary = {}
    for method in METHODS:
        values = [r[method] for r in results if r[method] is not None]
        summary[method] = {"views": len(values), "median_deg": statistics.median(values) if values else None,
                           "min_deg": min(values, default=None), "max_deg": max(values, default=None)}
        if values:
            print(f"{method}: median over {len(values)} views {summary[method]['median_deg']:.3f} deg, "
                  f"range {summary[method]['min_deg']:.3f}-{summary[method]['max_deg']:.3f}")
    out = pathlib.Path(args.out)
    out.parent.mkdir(parents=True, exist_ok=True)
    out.write_text(json.dumps({"args": vars(args), "views": [{"range_m": r, **res} for (_, r), res in
                                                             zip(views, results)], "summary": summary}, indent=1))
    print(f"wrote {out}")


if __name__ == "__main__":
    main()
