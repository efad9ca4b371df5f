#!/usr/bin/env python3
"""Replays one bag with several configurations and compares what perception makes of it (issue 13,
docs/TUNING.md). Two configurations (A/B) or one parameter swept over a list of values:

  tune_replay.py --bag B.bag --set disparity_detector.yaml:median_kernel_px=5          # A = config/, B = A + the edit
  tune_replay.py --bag B.bag --config-a DIR_A --config-b DIR_B                          # two folders
  tune_replay.py --bag B.bag --sweep mono_pose_visible.yaml:fast_threshold=5,10,20      # one run per value
  tune_replay.py --bag BOTH.bag --images raw,compressed     # what JPEG recording costs (record.launch images:=both)

Each configuration is config/ (or --config-a) copied to a temporary folder with its edits made in place
(scripts/tune/yaml_line_edit.py: one line changed, comments kept, an unknown key refused), then replayed
losslessly (launch/replay.launch lossless:=true dock:=false: every frame processed, so two runs differ
only by their configuration) on a master of its own, recording what the replay made. Per source
(disparity, mono_visible, mono_ir, and the arbiter's fused /target/estimate) the report gives the
detection rate, the error against the simulator's truth where the bag has it, the CPU time per frame,
and the stamp-by-stamp differences to the first configuration (A, or the sweep's first value)
(scripts/tune/tune_analysis.py). Written to --out: report.json, report.png, table.txt (also printed),
each configuration's folder, replay log and output bag.
--set with --sweep: the edits apply to every configuration of the sweep.
"""
import argparse
import dataclasses
import datetime
import json
import pathlib
import shutil
import sys

HERE = pathlib.Path(__file__).resolve().parent
sys.path.insert(0, str(HERE))
import rosbag  # noqa: E402

import launch_runner  # noqa: E402
import tune_analysis  # noqa: E402
import tune_report  # noqa: E402
from yaml_line_edit import KeyEditError, set_key  # noqa: E402

ROOT = HERE.parents[1]


@dataclasses.dataclass
class Edit:
    """One key of one file of the configuration folder, e.g. disparity_detector.yaml:median_kernel_px=5."""
    file: str
    key: str
    value: str

    def __str__(self):
        return "%s:%s=%s" % (self.file, self.key, self.value)


@dataclasses.dataclass
class Configuration:
    """A folder to copy and the edits to make in the copy."""
    label: str
    base_dir: pathlib.Path
    edits: list
    images: str = "auto"  # replay.launch images:= (auto, raw, compressed): which frames of the bag to play


class UsageError(Exception):
    """The user's request cannot be run as given; the message says why."""


def split_list(text):
    """v1,v2,v3 -> [v1, v2, v3]; commas inside [] or {} belong to a value (a list-valued key)."""
    values, depth, current = [], 0, ""
    for char in text:
        depth += char in "[{"
        depth -= char in "]}"
        if char == "," and depth == 0:
            values.append(current.strip())
            current = ""
        else:
            current += char
    values.append(current.strip())
    if any(not v for v in values):
        raise UsageError("empty value in the list %r" % text)
    return values


def parse_assignment(text, option):
    """FILE.yaml:KEY=VALUE -> (file, key, value). FILE is relative to the configuration folder; a
    leading config/ is accepted, as a user copying a path from the repository would write it."""
    file_part, sep, rest = text.partition(":")
    key, eq, value = rest.partition("=")
    if not sep or not eq or not file_part or not key.strip() or not value.strip():
        raise UsageError("%s %r: expected FILE.yaml:KEY=VALUE, e.g. disparity_detector.yaml:median_kernel_px=5"
                         % (option, text))
    file_part = file_part[len("config/"):] if file_part.startswith("config/") else file_part
    return file_part, key.strip(), value.strip()


def configurations_from(args):
    """The configurations to replay, in report order (the first is the reference)."""
    base = pathlib.Path(args.config_a or ROOT / "config").resolve()
    edits = [Edit(*parse_assignment(text, "--set")) for text in args.set]
    if args.images:
        # The images' cost, not a parameter's: one configuration, replayed from each kind of frame of a bag
        # recorded with record.launch images:=both.
        if args.sweep or args.config_b:
            raise UsageError("--images compares image sources under one configuration: not with --sweep or --config-b")
        kinds = split_list(args.images)
        unknown = [k for k in kinds if k not in ("raw", "compressed")]
        if unknown or len(kinds) < 2:
            raise UsageError("--images takes two or more of raw, compressed (got %r)" % args.images)
        return [Configuration("images=" + kind, base, edits, kind) for kind in kinds]
    if args.sweep:
        if args.config_b:
            raise UsageError("--sweep and --config-b: choose one")
        file, key, values = parse_assignment(args.sweep, "--sweep")
        return [Configuration("%s=%s" % (key, value), base, edits + [Edit(file, key, value)])
                for value in split_list(values)]
    if args.config_b:
        if edits:
            raise UsageError("--config-b and --set: put the edits in DIR_B, or use --set alone")
        return [Configuration("A", base, []), Configuration("B", pathlib.Path(args.config_b).resolve(), [])]
    if not edits:
        raise UsageError("nothing to compare: give --set, --config-b or --sweep")
    return [Configuration("A", base, []), Configuration("B: " + ", ".join("%s=%s" % (e.key, e.value) for e in edits),
                                                        base, edits)]


def prepare(configuration, folder):
    """Copies the configuration's folder to `folder` and makes its edits there; returns the old values.
    Everything is prepared before the first replay, so a misspelt key fails in a second, not after the
    other configurations have run."""
    if not (configuration.base_dir / "robot.yaml").is_file():
        raise UsageError("%s is not a configuration folder (no robot.yaml)" % configuration.base_dir)
    shutil.copytree(configuration.base_dir, folder)
    old_values = {}
    for edit in configuration.edits:
        path = folder / edit.file
        if not path.is_file():
            known = sorted(p.name for p in configuration.base_dir.glob("*.yaml"))
            raise UsageError("%s: no file %s in %s (files: %s)" % (edit, edit.file, configuration.base_dir,
                                                                   ", ".join(known)))
        try:
            old_values[str(edit)] = set_key(str(path), edit.key, edit.value)
        except KeyEditError as err:
            raise UsageError(str(err).replace(str(folder), str(configuration.base_dir)))
    return old_values


def check_bag(path):
    """Refuses, before any replay, a file that is not a bag or a bag without the cameras' images (e.g. a
    replay's own output, or a sim.launch bag:= recording, which holds no images)."""
    if not path.is_file():
        raise UsageError("no bag %s" % path)
    try:
        with rosbag.Bag(str(path)) as bag:
            topics = {tune_analysis.name_of(t) for t in bag.get_type_and_topic_info().topics}
    except (rosbag.ROSBagException, OSError) as err:
        raise UsageError("%s is not a readable bag (%s)" % (path, err))
    missing = [camera for camera in ("stereo/left", "stereo/right", "ir")
               if not {camera + "/image_raw", camera + "/image_raw/compressed"} & topics
               or camera + "/camera_info" not in topics]
    if missing:
        raise UsageError("%s has no images and camera_info of %s (its topics: %s); record with "
                         "launch/record.launch or scripts/tune/record_sim_bag.py"
                         % (path, ", ".join(missing), ", ".join(sorted(topics))))


def replay(bag, config_dir, out_bag, log_path, timeout_s, images="auto", port=None):
    """One lossless replay (on a master at `port`, else at a free port); raises UsageError with the nodes'
    own words when they refuse the configuration, RuntimeError when the replay fails otherwise."""
    result = launch_runner.run_launch(
        [str(ROOT / "launch" / "replay.launch"), "bag:=%s" % bag, "config_dir:=%s" % config_dir,
         "out:=%s" % out_bag, "lossless:=true", "dock:=false", "output:=screen", "images:=%s" % images],
        str(log_path), timeout_s, port=port)
    if result.failure_lines:
        raise UsageError("a node refused this configuration (%s):\n  %s" % (log_path, "\n  ".join(result.failure_lines)))
    if result.timed_out:
        raise RuntimeError("the replay did not end within %.0f s (log %s)" % (timeout_s, log_path))
    if not result.player_summary or not out_bag.is_file():
        raise RuntimeError("the replay ended without its summary or its output bag (exit %s, log %s)"
                           % (result.exit_code, log_path))
    if result.frames_played == 0:
        raise RuntimeError("the player published no complete camera frame (log %s)" % log_path)
    return result


def parse_args(argv):
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--bag", required=True, help="the bag to replay (record.launch or sim.launch bag:=, with images)")
    parser.add_argument("--set", action="append", default=[], metavar="FILE.yaml:KEY=VALUE",
                        help="an edit of configuration B (repeatable); with --sweep, of every configuration")
    parser.add_argument("--sweep", metavar="FILE.yaml:KEY=V1,V2,...", help="one configuration per value")
    parser.add_argument("--config-a", metavar="DIR", help="configuration A, the base of the edits (default: config/)")
    parser.add_argument("--config-b", metavar="DIR", help="configuration B as a whole folder")
    parser.add_argument("--out", help="output folder (default: results/tune/<date-time>/)")
    parser.add_argument("--images", metavar="raw,compressed",
                        help="replay one configuration from each kind of image frame of a bag recorded with "
                             "record.launch images:=both: what the JPEG recording costs the estimates")
    parser.add_argument("--timeout", type=float, default=1800.0, help="wall seconds allowed per replay")
    parser.add_argument("--port", type=int, help="the ROS master's port for every replay, one after the other "
                                                 "(default: a free port per replay)")
    return parser.parse_args(argv)


def main(argv=None):
    args = parse_args(argv)
    out = pathlib.Path(args.out or ROOT / "results" / "tune" / datetime.datetime.now().strftime("%Y%m%d-%H%M%S"))
    try:
        bag = pathlib.Path(args.bag).resolve()
        check_bag(bag)
        configurations = configurations_from(args)
        out.mkdir(parents=True, exist_ok=True)
        old_values = []
        for index, configuration in enumerate(configurations):
            folder = out / ("config_%d" % index)
            shutil.rmtree(folder, ignore_errors=True)
            old_values.append(prepare(configuration, folder))
        runs = []
        for index, configuration in enumerate(configurations):
            out_bag = out / ("replay_%d.bag" % index)
            print("tune_replay: [%d/%d] %s ..." % (index + 1, len(configurations), configuration.label), flush=True)
            result = replay(bag, out / ("config_%d" % index), out_bag, out / ("replay_%d.log" % index), args.timeout,
                            configuration.images, args.port)
            print("  " + result.player_summary, flush=True)
            runs.append((out_bag, result))
    except UsageError as err:
        sys.exit("tune_replay: %s" % err)
    except RuntimeError as err:
        sys.exit("tune_replay: replay failed: %s" % err)

    analysis = tune_analysis.analyse(str(bag), [str(path) for path, _ in runs])
    report = {
        "bag": str(bag),
        "truth": analysis["truth"],
        "camera_frames": analysis["frames"],
        "reference": configurations[0].label,
        "configurations": [
            {"label": c.label, "base_dir": str(c.base_dir), "edits": [str(e) for e in c.edits], "images": c.images,
             "replaced_values": old, "output_bag": str(path), "player": result.player_summary,
             "frames_lost": result.frames_lost, "sources": metrics}
            for c, old, (path, result), metrics in zip(configurations, old_values, runs, analysis["configurations"])],
    }
    with open(out / "report.json", "w") as stream:
        json.dump(report, stream, indent=2)
    table = tune_report.table(report)
    (out / "table.txt").write_text(table + "\n")
    tune_report.plot(report, str(out / "report.png"))
    print(table)
    print("tune_replay: wrote %s, %s, %s" % (out / "report.json", out / "report.png", out / "table.txt"))
    if any(result.frames_lost for _, result in runs):
        print("tune_replay: WARNING: some frames had no estimate within the player's timeout (see 'player')")


if __name__ == "__main__":
    main()
