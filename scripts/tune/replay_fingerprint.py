#!/usr/bin/env python3
"""What the stack makes of the sample bags, as one fingerprint: the check that a restructuring changes no
output (DEVELOPERS: "the lossless replay of bags/ gives identical estimates").

    scripts/tune/replay_fingerprint.py --out results/fingerprint/before.json       # replays bags/*.bag
    scripts/tune/replay_fingerprint.py --compare results/fingerprint/before.json results/fingerprint/after.json

Each bag is replayed losslessly with config/ (tune_replay.replay: every frame processed, a master of its
own). Every estimate on the estimators' and the arbiter's topics is written out field by field in stamp
order, without processing_time_ms (CPU time differs run to run); the file holds each topic's messages
and a SHA-256 of them. --compare prints the first difference per topic and exits 1 when any differs.
"""
import argparse
import hashlib
import json
import pathlib
import re
import sys
import tempfile

HERE = pathlib.Path(__file__).resolve().parent
sys.path.insert(0, str(HERE))
ROOT = HERE.parents[1]

TOPICS = ("/perception/disparity/estimate", "/perception/mono_visible/estimate", "/perception/mono_ir/estimate",
          "/target/estimate")


def canonical(msg):
    """Every field of a TargetEstimate but processing_time_ms, as one line of text."""
    fields = []
    for name in msg.__slots__:
        if name == "processing_time_ms":
            continue
        value = getattr(msg, name)
        fields.append("%s=%s" % (name, repr(value).replace("\n", " ")))
    return " ".join(fields)


def replay_bag(bag, work):
    import rosbag
    import tune_replay
    out_bag = work / (bag.stem + "_replay.bag")
    tune_replay.replay(bag, ROOT / "config", out_bag, work / (bag.stem + ".log"), timeout_s=1800.0)
    messages = {topic: [] for topic in TOPICS}
    with rosbag.Bag(str(out_bag)) as replayed:
        for topic, msg, _ in replayed.read_messages(topics=list(TOPICS)):
            messages[topic].append(canonical(msg))
    return {topic: {"messages": lines, "sha256": hashlib.sha256("\n".join(lines).encode()).hexdigest()}
            for topic, lines in messages.items()}


def fingerprint(out):
    result = {}
    with tempfile.TemporaryDirectory() as tmp:
        for bag in sorted((ROOT / "bags").glob("*.bag")):
            print("replay_fingerprint: %s ..." % bag.name, flush=True)
            result[bag.name] = replay_bag(bag, pathlib.Path(tmp))
            for topic, entry in result[bag.name].items():
                print("  %-36s %4d estimates  %s" % (topic, len(entry["messages"]), entry["sha256"][:16]))
    out.parent.mkdir(parents=True, exist_ok=True)
    out.write_text(json.dumps(result, indent=1))


STAGE_FIELDS = re.compile(r" stage=\d+ stage_outcome=\d+$")


def without_unshared_fields(a_lines, b_lines):
    """A fingerprint from before TargetEstimate had stage and stage_outcome compares on the other fields."""
    if any(STAGE_FIELDS.search(line) for line in a_lines) != any(STAGE_FIELDS.search(line) for line in b_lines):
        return [STAGE_FIELDS.sub("", line) for line in a_lines], [STAGE_FIELDS.sub("", line) for line in b_lines]
    return a_lines, b_lines


def compare(a_path, b_path):
    a, b = json.loads(pathlib.Path(a_path).read_text()), json.loads(pathlib.Path(b_path).read_text())
    differences = 0
    for bag in sorted(set(a) | set(b)):
        for topic in TOPICS:
            ea, eb = a.get(bag, {}).get(topic), b.get(bag, {}).get(topic)
            ma, mb = without_unshared_fields((ea or {}).get("messages", []), (eb or {}).get("messages", []))
            if ea and eb and ma == mb:
                print("same       %s %s (%d estimates)" % (bag, topic, len(ma)))
                continue
            differences += 1
            first = next((i for i, (x, y) in enumerate(zip(ma, mb)) if x != y), min(len(ma), len(mb)))
            print("DIFFERENT  %s %s: %d vs %d estimates, first difference at #%d" % (bag, topic, len(ma), len(mb), first))
            if first < len(ma) and first < len(mb):
                print("   a: %s\n   b: %s" % (ma[first][:400], mb[first][:400]))
    return 1 if differences else 0


def main():
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--out", help="write the fingerprint of a replay of bags/ here")
    parser.add_argument("--compare", nargs=2, metavar=("A", "B"), help="compare two fingerprints")
    args = parser.parse_args()
    if args.compare:
        sys.exit(compare(*args.compare))
    if not args.out:
        parser.error("--out or --compare")
    fingerprint(pathlib.Path(args.out))


if __name__ == "__main__":
    main()
