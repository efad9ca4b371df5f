#!/usr/bin/env python3
"""make eval: runs a fixed set of simulator scenarios with perception only, compares every estimate
with the truth at its stamp, and writes results/eval/summary.json and PNG plots.

Each scenario runs launch/eval.launch on its own ROS master (a free port), with
scripts/eval/eval_recorder.py beside it. Sim time runs at --real-time-factor (default 0.5) so that
perception keeps up on a 2-core machine; results are in sim time and do not depend on it.
"""
import argparse
import json
import os
import pathlib
import signal
import subprocess
import sys
import time

ROOT = pathlib.Path(__file__).resolve().parents[2]
sys.path.insert(0, str(ROOT / "scripts" / "tune"))
from launch_runner import free_port  # noqa: E402  (one copy: masters outside the ephemeral ports)

# (scenario, lighting). The far set is issue 4's; the near, rotating, dark and glare ones issue 5's.
FAR = [(f"eval_far_{r}m_{p}", "nominal") for r in ("2", "3", "4", "6") for p in ("on", "off")]
NEAR = [(f"eval_near_{r}m_{p}", "nominal") for r in ("0p4", "0p7", "1", "1p4", "2") for p in ("on", "off")]
SPECIAL = [("eval_rotating_1m", "nominal"), ("eval_dark_1m", "dark"), ("eval_glare_1m", "glare"),
           ("eval_roll20_1m", "nominal"), ("eval_tilt15_1p4m", "nominal")]


def realistic_scenarios():
    """Issue 11's scenarios (config/scenarios/eval_real_*.yaml: blur, exposure, glare, clutter), each with
    the lighting its file names."""
    import yaml
    found = []
    for path in sorted((ROOT / "config" / "scenarios").glob("eval_real_*.yaml")):
        lighting = (yaml.safe_load(path.read_text()).get("scenario") or {}).get("lighting", "nominal")
        found.append((path.stem, lighting))
    return found


REALISTIC = realistic_scenarios()
SETS = {"far": FAR, "near": NEAR, "special": SPECIAL, "realistic": REALISTIC,
        "all": FAR + NEAR + SPECIAL + REALISTIC}



def scenario_range(name):
    """The nominal camera-to-port range written into the scenario's name (eval_far_3m_on -> 3.0)."""
    for part in name.split("_"):
        if part.endswith("m") and part[:-1].replace("p", "").isdigit():
            return float(part[:-1].replace("p", "."))
    return None


def run_scenario(name, lighting, args, raw_dir, log_dir):
    port = free_port()
    env = dict(os.environ, ROS_MASTER_URI=f"http://127.0.0.1:{port}", ROS_HOME=str(log_dir / "ros_home"))
    out_json = raw_dir / f"{name}.json"
    out_json.unlink(missing_ok=True)
    log = open(log_dir / f"{name}.log", "w")
    launch = subprocess.Popen(
        ["roslaunch", "-p", str(port), str(ROOT / "launch" / "eval.launch"), f"scenario:={name}",
         f"real_time_factor:={args.real_time_factor}"],
        env=env, stdout=log, stderr=subprocess.STDOUT, start_new_session=True)
    recorder_args = ["/usr/bin/python3", str(ROOT / "scripts" / "eval" / "eval_recorder.py"),
                     f"_output:={out_json}", f"_scenario:={name}", f"_lighting:={lighting}",
                     f"_warmup_s:={args.warmup}", f"_duration_s:={args.duration}"]
    nominal = scenario_range(name)
    if nominal is not None:
        recorder_args.append(f"_range_m:={nominal}")
    try:
        # The recorder starts once the master answers and the launch has set use_sim_time.
        deadline = time.time() + 60.0
        while time.time() < deadline and launch.poll() is None:
            probe = subprocess.run(["rosparam", "get", "/use_sim_time"], env=env, stdout=subprocess.PIPE,
                                   stderr=subprocess.DEVNULL, text=True)
            if probe.returncode == 0 and probe.stdout.strip() == "true":
                break
            time.sleep(0.5)
        recorder = subprocess.run(recorder_args, env=env, stdout=log, stderr=subprocess.STDOUT,
                                  timeout=args.timeout)
        ok = recorder.returncode == 0 and out_json.exists()
    except subprocess.TimeoutExpired:
        ok = False
    finally:
        os.killpg(launch.pid, signal.SIGINT)
        try:
            launch.wait(timeout=20)
        except subprocess.TimeoutExpired:
            pass
        # Whatever roslaunch left behind in its process group (a master interrupted while starting).
        try:
            os.killpg(launch.pid, signal.SIGKILL)
        except ProcessLookupError:
            pass
        log.close()
    if not ok:
        print(f"  {name}: FAILED (see {log_dir / (name + '.log')})")
        return None
    return json.loads(out_json.read_text())


def coverage_text(entry):
    """The worst per-axis share of errors within 3 sigma, and its axis ("n/a" when nothing claimed)."""
    shares = [(share, axis) for axis, share in (entry.get("within_3_sigma") or {}).items() if share is not None]
    if not shares:
        return "n/a"
    share, axis = min(shares)
    return f"{share:.2f} ({axis})"


def plot(scenarios, out_dir):
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, axes = plt.subplots(1, 2, figsize=(11, 4))
    markers = {"disparity": "o", "mono_visible": "s", "mono_ir": "^", "fused": "x"}
    for source, marker in markers.items():
        pts = [(s["range_m"], s["sources"][source]) for s in scenarios if source in s["sources"]]
        pts = [(r, v) for r, v in pts if v["position_error_median_m"] is not None]
        if not pts:
            continue
        pts.sort(key=lambda rv: rv[0])
        # Range error in cm (the stereo limit is a depth error); position error adds the lateral part.
        axes[0].plot([r for r, _ in pts], [r * v["range_error_median_pct"] for r, v in pts], marker,
                     label=source, linestyle="none")
        axes[1].plot([r for r, _ in pts], [v["detection_rate"] for _, v in pts], marker, label=source,
                     linestyle="none")
    ranges = [s["range_m"] for s in scenarios]
    if ranges:
        import numpy as np
        z = np.linspace(max(0.3, min(ranges)), max(ranges), 50)
        # Stereo limit: Z^2 * 0.25 px / (f b), f = 550 px, b = 0.10 m; the goal is twice that.
        axes[0].plot(z, 100 * 2 * z ** 2 * 0.25 / (550 * 0.10), "k--", label="goal: 2x stereo limit")
    axes[0].set_xlabel("true range at start [m]")
    axes[0].set_ylabel("median range error [cm]")
    axes[0].set_yscale("log")
    axes[0].grid(True, which="both", alpha=0.3)
    axes[0].legend()
    axes[1].set_xlabel("true range at start [m]")
    axes[1].set_ylabel("detection rate")
    axes[1].set_ylim(-0.05, 1.05)
    axes[1].grid(True, alpha=0.3)
    fig.suptitle("Perception against simulator ground truth (make eval)")
    fig.tight_layout()
    fig.savefig(out_dir / "error_vs_range.png", dpi=100)
    plt.close(fig)

    # Error over time, one panel per scenario with any valid estimate.
    with_raw = [s for s in scenarios if s.get("raw")]
    if with_raw:
        cols = 4
        rows = (len(with_raw) + cols - 1) // cols
        fig, axes = plt.subplots(rows, cols, figsize=(4 * cols, 2.6 * rows), squeeze=False)
        for ax, s in zip(axes.flat, with_raw):
            for source, samples in s["raw"].items():
                t = [x["t"] for x in samples if x["position_error"] is not None]
                e = [100 * x["position_error"] for x in samples if x["position_error"] is not None]
                ax.plot(t, e, ".", markersize=2, label=source)
            ax.set_title(s["name"], fontsize=8)
            ax.set_ylabel("pos. error [cm]", fontsize=7)
            ax.tick_params(labelsize=6)
        for ax in list(axes.flat)[len(with_raw):]:
            ax.axis("off")
        axes.flat[0].legend(fontsize=6)
        fig.tight_layout()
        fig.savefig(out_dir / "error_over_time.png", dpi=90)
        plt.close(fig)


def main():
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--set", default="all", choices=sorted(SETS))
    parser.add_argument("--only", nargs="*", help="scenario names (overrides --set)")
    parser.add_argument("--warmup", type=float, default=3.0, help="sim seconds before recording")
    parser.add_argument("--duration", type=float, default=8.0, help="sim seconds recorded per scenario")
    parser.add_argument("--real-time-factor", type=float, default=0.5)
    parser.add_argument("--timeout", type=float, default=240.0, help="wall seconds per scenario at most")
    parser.add_argument("--out", default=str(ROOT / "results" / "eval"))
    parser.add_argument("--plot-only", action="store_true",
                        help="rebuild summary.json and the plots from the raw results of earlier runs")
    args = parser.parse_args()

    out_dir = pathlib.Path(args.out)
    raw_dir, log_dir = out_dir / "raw", out_dir / "logs"
    raw_dir.mkdir(parents=True, exist_ok=True)
    log_dir.mkdir(parents=True, exist_ok=True)
    runs = [(n, dict(SETS["all"]).get(n, "nominal")) for n in args.only] if args.only else SETS[args.set]

    scenarios, failed = [], []
    if args.plot_only:
        names = [n for n, _ in runs]
        scenarios = [json.loads((raw_dir / f"{n}.json").read_text()) for n in names if (raw_dir / f"{n}.json").exists()]
        runs = []
    for name, lighting in runs:
        print(f"eval: {name} ({lighting})", flush=True)
        result = run_scenario(name, lighting, args, raw_dir, log_dir)
        if result is None:
            failed.append(name)
            continue
        scenarios.append(result)
        for source, v in sorted(result["sources"].items()):
            err = v["position_error_median_m"]
            print(f"  {source:13s} frames {v['frames']:4d}  detection {v['detection_rate']:.2f}  "
                  f"pos err median {('%.4f m' % err) if err is not None else '   n/a '}  "
                  f"range err {('%.2f %%' % v['range_error_median_pct']) if v['range_error_median_pct'] is not None else 'n/a'}  "
                  f"{v['rate_hz']:.1f} Hz  {v['processing_ms_median'] or 0:.1f} ms  "
                  f"wrong {v.get('confident_wrong', 0)}  3-sigma {coverage_text(v)}", flush=True)

    summary = {"scenarios": [{k: s[k] for k in ("name", "range_m", "lighting", "sources")} for s in scenarios]}
    (out_dir / "summary.json").write_text(json.dumps(summary, indent=2))
    plot(scenarios, out_dir)
    print(f"eval: {len(scenarios)} scenarios written to {out_dir / 'summary.json'}; plots in {out_dir}")
    if failed:
        print(f"eval: {len(failed)} scenarios failed to run: {', '.join(failed)}")
        return 1
    return 0


if __name__ == "__main__":
    sys.exit(main())
