#!/usr/bin/env python3
"""Instructions per frame of the perception stages, counted by callgrind, for scripts/arm64_bench_instructions.sh.

The stages, frame counts and calls of scripts/bench_instructions.py (imported from it), on bench programs built
outside the workspace, under any valgrind command: the host's valgrind for x86-64, or Debian's arm64 valgrind
under qemu-aarch64-static (a wrapper script) for arm64.

  arm64_bench_instructions.py OUT.json --bin DIR --config DIR --valgrind CMD --mono-shim SO --far-shim SO
      [--shim-env LD_PRELOAD] [--jobs 2] [--stages mono_full,mono_tracking,...]
      [--far-left L.png --far-right R.png] [--disparity full,window] [--compare X86.json]

Why not --toggle-collect as bench_instructions.py: --toggle-collect and inclusive costs rest on callgrind's
call-stack tracking, and under arm64 callgrind that is not reliable (bench_disparity's call graph had inclusive
costs above the program's total, with spurious recursion). So the stage's boundaries are marked by callgrind
client requests from an LD_PRELOAD shim (scripts/arm64_bench_shims/*.cpp) that wraps the library function the
bench program calls, which needs no call-stack tracking:
- mono (bench_mono --stages NAME, 90 frames): the shim wraps MonoPoseEstimator::process in CALLGRIND_TOGGLE_COLLECT
  (run with --collect-atstart=no) and switches instrumentation on when the stage's estimator is constructed (run
  with --instr-atstart=no: the 90 synthetic frames are rendered uninstrumented, ~4x faster);
- far stage (bench_disparity, 3 frames + 3 warm-up, divided by 6 as bench_instructions.py): the shim dumps
  callgrind's counters (CALLGRIND_DUMP_STATS_AT) before and after each call of cv::cvtColor and
  WindowRectifier::rectifyWindow (together: rectify), DisparityDetector::detect (detection) and
  confirmByAppearance (appearance); the dump between the last rectifyWindow and detect is disparity
  (computeDisparity, plus the loop's few clock reads). --window: runs of 3 and 6 frames differenced, as
  bench_instructions.py does, which leaves out the untimed pass that places the window.
Checked on x86-64 against bench_instructions.py's --toggle-collect counts of the same binaries: mono_ir
159,070,297 against 159,068,984 instructions (90 frames); far stage per call rectify 24.90, disparity 191.84,
detection 25.23, appearance 2.16 M with both methods (they differ by 0.3-1.6 k instructions a call).
"""
import argparse
import collections
import concurrent.futures
import json
import os
import pathlib
import re
import shlex
import subprocess
import sys
import tempfile
import time

HERE = pathlib.Path(__file__).resolve().parent
sys.path.insert(0, str(HERE))
import bench_instructions as bi  # noqa: E402  (the stage definitions counted on x86 by `make bench`)


def run_callgrind(args, options, command, shim):
    """Runs command under callgrind with the shim preloaded; returns (collected instructions, stdout)."""
    env = dict(os.environ)
    env[args.shim_env] = shim
    run = subprocess.run(shlex.split(args.valgrind) + ["--tool=callgrind"] + options + [str(c) for c in command],
                         capture_output=True, text=True, env=env, check=False)
    found = re.search(r"Collected\s*:\s*(\d+)", run.stderr)
    if run.returncode != 0 or not found:
        tail = "\n".join(run.stderr.strip().splitlines()[-5:])
        raise bi.CountError(f"{' '.join(map(str, command))} under callgrind failed (exit {run.returncode}): {tail}")
    return int(found.group(1)), run.stdout


def count_mono(stage, args, workdir):
    options = [f"--callgrind-out-file={pathlib.Path(workdir) / ('cg.' + stage)}", "--instr-atstart=no",
               "--collect-atstart=no"]
    command = [pathlib.Path(args.bin) / "bench_mono", pathlib.Path(workdir) / f"{stage}.json",
               pathlib.Path(args.config) / "target.yaml", "--stages", stage]
    instructions, stdout = run_callgrind(args, options, command, args.mono_shim)
    frames = re.search(r"(\d+) frames", stdout)
    if not frames or instructions == 0:
        raise bi.CountError(f"{stage}: no frame count, or nothing collected (was the shim loaded?)")
    figures = bi.per_frame(instructions, int(frames.group(1)))
    figures["instructions"] = instructions
    # bench_mono's accuracy line (detection rate, errors, tracked fraction): the same behaviour on both machines?
    figures["bench_line"] = next((line for line in stdout.splitlines() if line.startswith(stage + " ")), "")
    return {stage: figures}


def dump_sums(prefix):
    """{label: instructions summed over its dumps} of callgrind's dump files prefix.1, prefix.2, ..."""
    sums, counts = collections.defaultdict(int), collections.Counter()
    for dump in pathlib.Path(prefix).parent.glob(pathlib.Path(prefix).name + ".*"):
        head = dump.read_text(errors="replace")[:100000]
        label = re.search(r"^desc: Trigger: Client Request: (\S+)", head, re.M)
        total = re.search(r"^(?:totals|summary): (\d+)", head, re.M)
        if label and total:
            sums[label.group(1)] += int(total.group(1))
            counts[label.group(1)] += 1
    return sums, counts


def disparity_run(args, workdir, name, extra, frames):
    """One bench_disparity run with the far shim: {stage: instructions summed over the run's calls}."""
    prefix = pathlib.Path(workdir) / f"cg.disparity_{name}_{frames}"
    command = [pathlib.Path(args.bin) / "bench_disparity", pathlib.Path(workdir) / f"disparity_{name}.json",
               "--frames", frames, "--config-dir", args.config, "--left", args.far_left,
               "--right", args.far_right] + extra
    run_callgrind(args, [f"--callgrind-out-file={prefix}"], command, args.far_shim)
    sums, counts = dump_sums(prefix)
    if counts["detect"] == 0 or counts["rectifyWindow"] == 0:
        raise bi.CountError(f"{name}: no dumps from the far shim (was it loaded?)")
    return {"rectify": sums["cvtColor"] + sums["rectifyWindow"], "disparity": sums["detect_pre"],
            "detection": sums["detect"], "appearance": sums["appearance"]}


def count_disparity(config, args, workdir):
    stages = {}
    if config == "full":
        prefix = ""
        counts = disparity_run(args, workdir, config, [], bi.DISPARITY_FRAMES)
        calls = bi.DISPARITY_FRAMES + bi.DISPARITY_WARMUP
        for stage, instructions in counts.items():
            stages[prefix + stage] = bi.per_frame(instructions, calls)
    else:  # window: the untimed placing pass left out by differencing 3 and 6 frames
        prefix = "window_"
        short, long = bi.DISPARITY_FRAMES, 2 * bi.DISPARITY_FRAMES
        a = disparity_run(args, workdir, "window", ["--window"], short)
        b = disparity_run(args, workdir, "window", ["--window"], long)
        for stage in a:
            stages[prefix + stage] = bi.per_frame(b[stage] - a[stage], long - short)
    total = sum(stages[prefix + s]["instructions_per_frame_M"] for s in bi.DISPARITY_STAGE_FUNCTIONS)
    frames = stages[prefix + "rectify"]["frames"]
    stages[prefix + "disparity_total"] = {"instructions_per_frame_M": round(total, 2), "frames": frames}
    return stages


def timed(job, name, args, workdir):
    """job(name, args, workdir), each of its stages with the run's wall time (wall_s)."""
    start = time.monotonic()
    result = job(name, args, workdir)
    for figures in result.values():
        figures["wall_s"] = round(time.monotonic() - start)
    return result


def main():
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("out")
    parser.add_argument("--bin", required=True, help="folder with bench_mono and bench_disparity")
    parser.add_argument("--config", required=True, help="the repository's config/ folder")
    parser.add_argument("--valgrind", default="valgrind", help="valgrind command (a wrapper for arm64)")
    parser.add_argument("--mono-shim", required=True, help="LD_PRELOAD library marking process() (mono_shim.cpp)")
    parser.add_argument("--far-shim", required=True, help="LD_PRELOAD library dumping per stage (far_shim.cpp)")
    parser.add_argument("--shim-env", default="LD_PRELOAD",
                        help="variable that carries the shim (the arm64 wrapper's: GUEST_LD_PRELOAD)")
    parser.add_argument("--stages", default="mono_full,mono_tracking,mono_tracking_near,mono_ir")
    parser.add_argument("--disparity", default="full", help="far stage configurations: full,window or ''")
    parser.add_argument("--far-left")
    parser.add_argument("--far-right")
    parser.add_argument("--jobs", type=int, default=2)
    parser.add_argument("--compare", help="another run's OUT.json (x86) to print beside")
    args = parser.parse_args()
    tasks = [("disparity", c) for c in args.disparity.split(",") if c]
    tasks += [("mono", s) for s in args.stages.split(",") if s]
    if any(kind == "disparity" for kind, _ in tasks) and not (args.far_left and args.far_right):
        parser.error("the far stage needs --far-left and --far-right")
    stages = {}
    failed = 0
    with tempfile.TemporaryDirectory() as workdir, \
            concurrent.futures.ThreadPoolExecutor(max_workers=max(1, min(2, args.jobs))) as pool:
        futures = {}
        for kind, name in tasks:  # the far stage first: its full-resolution run is the longest under arm64
            job = count_disparity if kind == "disparity" else count_mono
            futures[pool.submit(timed, job, name, args, workdir)] = name
        for future in concurrent.futures.as_completed(futures):
            try:
                result = future.result()
            except bi.CountError as error:
                print(f"arm64_bench_instructions: {futures[future]}: {error}", file=sys.stderr)
                failed += 1
                continue
            stages.update(result)
            for name, figures in result.items():
                print(f"  {name:24s} {figures['instructions_per_frame_M']:9.2f} M  ({figures['wall_s']} s)", flush=True)
            pathlib.Path(args.out).write_text(json.dumps({"stages": stages}, indent=2) + "\n")
    other = json.loads(pathlib.Path(args.compare).read_text())["stages"] if args.compare else {}
    print(f"instructions per frame (callgrind, M): {args.out}")
    for name in sorted(stages):
        beside = other.get(name, {}).get("instructions_per_frame_M")
        ratio = f"  ({stages[name]['instructions_per_frame_M'] / beside:.3f}x)" if beside else ""
        print(f"  {name:24s} {stages[name]['instructions_per_frame_M']:9.2f} M"
              + (f"   compared: {beside:9.2f} M{ratio}" if beside else "")
              + f"  (over {stages[name]['frames']} frames)")
    return 1 if failed else 0


if __name__ == "__main__":
    sys.exit(main())
