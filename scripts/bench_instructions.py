#!/usr/bin/env python3
"""Instructions per frame of each perception stage, counted by callgrind (part of `make bench`).

Times depend on the machine and on its load; instruction counts do not, so they predict the cost on a
slower computer (divide by its instructions per second) and compare runs taken under different loads.
Each stage runs in its own bench program under `valgrind --tool=callgrind`, collecting only inside the
function that does the stage's work (--toggle-collect); the count is divided by the number of calls.

  bench_instructions.py OUT.json --far-left L.png --far-right R.png --tagged-sequence DIR --tagged-target Y

Writes {"stages": {NAME: {"instructions_per_frame_M": float, "frames": int}}}. Stages:
  rectify, disparity, detection, appearance,      bench_disparity on the rendered far pair (per pair), full
  disparity_total (the four summed)               image; window_*: on the tracking window alone
                                                  (far_stereo.yaml window_*, the default while tracking)
  mono_full, mono_tracking,                       bench_mono's 90-frame approach (MonoPoseEstimator::process);
  mono_tracking_features, mono_ir                 mono_tracking_features: tracking by the feature search (before);
  mono_tracking_near                              tracking on bench_mono's second approach, 0.6 m to 0.2 m
  apriltag, mono_full_same_frame,                 bench_apriltag on one frame of the target with a tag
  mono_tracking_same_frame                        inset (AprilTag 3, then our pose on the same pixels)
Under callgrind the programs run ~50x slower: about 3 minutes in all on this machine.
"""
import argparse
import json
import pathlib
import re
import shutil
import subprocess
import sys
import tempfile

ROOT = pathlib.Path(__file__).resolve().parent.parent
LIB = ROOT / "devel" / "lib" / "docking_perception"
DISPARITY_FRAMES = 3  # timed frames; bench_disparity adds 3 warm-up frames, counted too
DISPARITY_WARMUP = 3
APRILTAG_FRAMES = 5   # bench_apriltag adds one warm-up call per stage, counted too
MONO_STAGES = ("mono_full", "mono_tracking", "mono_tracking_near", "mono_tracking_features", "mono_ir")
# The function whose every call is one frame of the stage.
DISPARITY_STAGE_FUNCTIONS = {
    "rectify": "*rectifyPair*",
    "disparity": "docking_perception::disparity::testing::computeDisparity*",
    "detection": "docking_perception::disparity::DisparityDetector::detect*",
    # The face print looked for where the blob puts the port (face_appearance.h): part of the detection.
    "appearance": "docking_perception::disparity::confirmByAppearance*",
}
MONO_FUNCTION = "docking_perception::mono::MonoPoseEstimator::process*"
APRILTAG_FUNCTION = "docking_perception::mono::TagDetector::detect*"


class CountError(RuntimeError):
    pass


def collected_instructions(command, toggle, workdir):
    """Runs command under callgrind collecting inside `toggle`; returns (instructions, program stdout)."""
    out_file = pathlib.Path(workdir) / "callgrind.out"
    run = subprocess.run(["valgrind", "--tool=callgrind", f"--callgrind-out-file={out_file}",
                          f"--toggle-collect={toggle}"] + [str(c) for c in command],
                         capture_output=True, text=True, check=False)
    found = re.search(r"Collected\s*:\s*(\d+)", run.stderr)
    if run.returncode != 0 or not found:
        raise CountError(f"{' '.join(map(str, command))} under callgrind failed (exit {run.returncode}): "
                         f"{run.stderr.strip().splitlines()[-1] if run.stderr.strip() else 'no output'}")
    if int(found.group(1)) == 0:
        raise CountError(f"no instruction collected inside {toggle}: was the function renamed?")
    return int(found.group(1)), run.stdout


def per_frame(instructions, frames):
    return {"instructions_per_frame_M": round(instructions / frames / 1e6, 2), "frames": frames}


def count_disparity(args, workdir):
    stages = {}
    calls = DISPARITY_FRAMES + DISPARITY_WARMUP
    command = [LIB / "bench_disparity", pathlib.Path(workdir) / "disparity.json", "--frames", DISPARITY_FRAMES,
               "--config-dir", ROOT / "config", "--left", args.far_left, "--right", args.far_right]
    for stage, function in DISPARITY_STAGE_FUNCTIONS.items():
        instructions, _ = collected_instructions(command, function, workdir)
        stages[stage] = per_frame(instructions, calls)
    total = sum(stages[s]["instructions_per_frame_M"] for s in DISPARITY_STAGE_FUNCTIONS)
    stages["disparity_total"] = {"instructions_per_frame_M": round(total, 2), "frames": calls}
    stages.update(count_disparity_window(args, workdir))
    return stages


def count_disparity_window(args, workdir):
    """The stage on the tracking window. bench_disparity --window places the window with one untimed pass
    over the whole image, which calls the same functions: two runs of different lengths, and the difference
    of their counts over the difference of their calls, leave that pass out exactly."""
    stages = {}
    short, long = DISPARITY_FRAMES, 2 * DISPARITY_FRAMES
    for stage, function in DISPARITY_STAGE_FUNCTIONS.items():
        counts = []
        for frames in (short, long):
            command = [LIB / "bench_disparity", pathlib.Path(workdir) / "disparity.json", "--frames", frames,
                       "--config-dir", ROOT / "config", "--left", args.far_left, "--right", args.far_right,
                       "--window"]
            counts.append(collected_instructions(command, function, workdir)[0])
        stages["window_" + stage] = per_frame(counts[1] - counts[0], long - short)
    total = sum(stages["window_" + s]["instructions_per_frame_M"] for s in DISPARITY_STAGE_FUNCTIONS)
    stages["window_disparity_total"] = {"instructions_per_frame_M": round(total, 2), "frames": long - short}
    return stages


def count_mono(workdir):
    stages = {}
    for stage in MONO_STAGES:
        command = [LIB / "bench_mono", pathlib.Path(workdir) / "mono.json", ROOT / "config" / "target.yaml",
                   "--stages", stage]
        instructions, stdout = collected_instructions(command, MONO_FUNCTION, workdir)
        frames = re.search(r"(\d+) frames", stdout)
        if not frames:
            raise CountError("bench_mono did not print its frame count")
        stages[stage] = per_frame(instructions, int(frames.group(1)))
    return stages


def count_same_frame(args, workdir):
    """AprilTag and our mono pose on the same frame, each stage in its own run."""
    stages = {}
    for stage, function in (("apriltag", APRILTAG_FUNCTION), ("mono_full_same_frame", MONO_FUNCTION),
                            ("mono_tracking_same_frame", MONO_FUNCTION)):
        command = [LIB / "bench_apriltag", pathlib.Path(workdir) / "apriltag.json", "--sequence",
                   args.tagged_sequence, "--target", args.tagged_target, "--mono-params",
                   ROOT / "config" / "mono_pose_visible.yaml", "--stages", stage, "--frames", APRILTAG_FRAMES]
        instructions, _ = collected_instructions(command, function, workdir)
        stages[stage] = per_frame(instructions, APRILTAG_FRAMES + 1)
    return stages


def main():
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("out")
    parser.add_argument("--far-left", required=True)
    parser.add_argument("--far-right", required=True)
    parser.add_argument("--tagged-sequence", required=True)
    parser.add_argument("--tagged-target", required=True)
    args = parser.parse_args()
    if shutil.which("valgrind") is None:
        print("bench_instructions: valgrind is not installed (make deps installs it): no instruction counts",
              file=sys.stderr)
        return 1
    stages = {}
    try:
        with tempfile.TemporaryDirectory() as workdir:
            stages.update(count_disparity(args, workdir))
            stages.update(count_mono(workdir))
            if (LIB / "bench_apriltag").exists():  # built only where libapriltag-dev is installed
                stages.update(count_same_frame(args, workdir))
    except CountError as error:
        print(f"bench_instructions: {error}", file=sys.stderr)
        return 1
    pathlib.Path(args.out).write_text(json.dumps({"stages": stages}, indent=2) + "\n")
    print("instructions per frame (callgrind, M):")
    for name, figures in stages.items():
        print(f"  {name:24s} {figures['instructions_per_frame_M']:9.2f} M  (over {figures['frames']} frames)")
    return 0


if __name__ == "__main__":
    sys.exit(main())
