#!/usr/bin/env python3
"""Analysis of one docking run from its bag: the outcome measured against the simulator's TRUTH, the
planner's state timeline, the arbiter's source timeline, the perception error per source
(scripts/eval/eval_recorder.py's pairing of estimates with truth at their stamps, reused), and PNG plots.
Used by scripts/demo/run_demo.py and scripts/demo/run_campaign.py;
standalone:  analyze_run.py RUN.bag OUT_DIR [--probe-x 0.18]

Bags it reads:
  - launch/sim.launch bag:=FILE (the simulator): everything above.
  - launch/record.launch (the robot; images, tf, odometry, estimates, docking/state): no truth unless
    extra_topics added it, so no docking or perception errors: the states, the sources in use and each
    estimator's detection rate, and a list of what the bag lacks. trajectory.png needs the truth.
  - older bags whose topics have no leading slash (`docking/state`): names are read either way.
Images in a bag are not read (only the topics below), so a robot bag is read in seconds.
"""
import argparse
import bisect
import json
import logging
import math
import pathlib
import sys

ROOT = pathlib.Path(__file__).resolve().parents[2]
sys.path.insert(0, str(ROOT / "scripts" / "eval"))
from eval_recorder import EvalRecorder, SOURCES, TRUTH_TOPICS  # noqa: E402  (reused, not copied)

# What each topic gives the analysis (absolute names; a bag may hold them without the leading slash).
TOPIC_CONTENTS = {
    "/tf": "truth poses of both robots (world -> chaser_truth / target_truth) and world -> odom",
    "/docking/state": "the planner's state, range and source in use",
    "/target/arbiter_status": "the arbiter's status text",
    "/docking/path": "the planned paths",
    "/docking/dock/goal": "the docking goal's time (times count from it)",
    "/cmd_vel": "velocity commands",
    **{topic: f"truth at the image stamps ({frame})" for frame, topic in TRUTH_TOPICS.items()},
    **{topic: f"{name} estimates" for name, topic in SOURCES.items()},
}
READ_TOPICS = set(TOPIC_CONTENTS) | {"/tf_static"}
STATE_NAMES = ["SEARCH", "APPROACH", "ALIGN", "FINAL", "DOCKED", "HOLD", "ABORT", "IDLE"]
SOURCE_NAMES = ["disparity", "mono_visible", "mono_ir", "fused"]
DOCKED = 4


def yaw_of(q):
    return math.atan2(2.0 * (q.w * q.z + q.x * q.y), 1.0 - 2.0 * (q.y * q.y + q.z * q.z))


def wrap(a):
    return math.atan2(math.sin(a), math.cos(a))


def probe_x_from_robot_yaml(path=ROOT / "config" / "robot.yaml"):
    import yaml
    with open(path) as f:
        return float(yaml.safe_load(f)["chaser"]["docking_probe_x_m"])


class Series:
    """Time series of planar poses (t, x, y, yaw), nearest-sample lookup."""

    def __init__(self):
        self.t, self.x, self.y, self.yaw = [], [], [], []

    def add(self, t, x, y, yaw):
        if self.t and t < self.t[-1]:
            return
        self.t.append(t)
        self.x.append(x)
        self.y.append(y)
        self.yaw.append(yaw)

    def at(self, t):
        if not self.t:
            return None
        i = bisect.bisect_left(self.t, t)
        if i >= len(self.t):
            i = len(self.t) - 1
        elif i > 0 and abs(self.t[i - 1] - t) < abs(self.t[i] - t):
            i -= 1
        return self.t[i], self.x[i], self.y[i], self.yaw[i]


def docking_errors(chaser, port, probe_x):
    """Probe tip (base_link x = probe_x, true chaser pose) against the true port origin, floor plane;
    yaw: chaser x against the reversed port axis."""
    _, cx, cy, cyaw = chaser
    _, px, py, pyaw = port
    tx, ty = cx + probe_x * math.cos(cyaw), cy + probe_x * math.sin(cyaw)
    return math.hypot(tx - px, ty - py), math.degrees(abs(wrap(cyaw - (pyaw + math.pi))))


def segments(samples):
    """[(t, value)] -> [{"start_s", "end_s", "value"}] of runs of equal values."""
    out = []
    for t, v in samples:
        if out and out[-1]["value"] == v:
            out[-1]["end_s"] = t
        else:
            out.append({"start_s": t, "end_s": t, "value": v})
    return out


def canonical_topic(name):
    """Older recorders stored relative names (`docking/state`); both forms mean the same topic here."""
    return "/" + name.lstrip("/")


def read_bag(bag_path):
    import rosbag
    data = {"chaser": Series(), "port": Series(), "states": [], "arbiter": [], "paths": [],
            "truth": {frame: {} for frame in TRUTH_TOPICS}, "estimates": {n: [] for n in SOURCES},
            "world_to_odom": None, "cmd_vel": [], "goal_times": [], "topics": set(), "span": None}
    truth_topic_frame = {topic: frame for frame, topic in TRUTH_TOPICS.items()}
    source_topic = {topic: name for name, topic in SOURCES.items()}
    last_clock = None
    with rosbag.Bag(str(bag_path)) as bag:
        stored = [t for t in bag.get_type_and_topic_info().topics if canonical_topic(t) in READ_TOPICS]
        data["topics"] = {canonical_topic(t) for t in stored}
        if bag.get_message_count():
            data["span"] = (bag.get_start_time(), bag.get_end_time())
        # Only these topics (an empty list would read every topic, images included).
        for stored_topic, msg, t in (bag.read_messages(topics=stored) if stored else ()):
            topic = canonical_topic(stored_topic)
            last_clock = t.to_sec()
            if topic in ("/tf", "/tf_static"):
                for tr in msg.transforms:
                    parent, child = tr.header.frame_id.lstrip("/"), tr.child_frame_id.lstrip("/")
                    if parent != "world":
                        continue
                    p, q = tr.transform.translation, tr.transform.rotation
                    pose = (tr.header.stamp.to_sec(), p.x, p.y, yaw_of(q))
                    if child == "chaser_truth":
                        data["chaser"].add(*pose)
                    elif child == "target_truth":
                        data["port"].add(*pose)
                    elif child == "odom":
                        data["world_to_odom"] = pose
            elif topic == "/docking/state":
                data["states"].append(msg)
            elif topic == "/target/arbiter_status":
                data["arbiter"].append((last_clock, msg.data))
            elif topic == "/docking/path":
                data["paths"].append((msg.header.stamp.to_sec(),
                                      [(ps.pose.position.x, ps.pose.position.y) for ps in msg.poses]))
            elif topic in truth_topic_frame:
                data["truth"][truth_topic_frame[topic]][msg.header.stamp.to_nsec()] = msg
            elif topic in source_topic:
                data["estimates"][source_topic[topic]].append(msg)
            elif topic == "/docking/dock/goal":
                data["goal_times"].append(last_clock)
            elif topic == "/cmd_vel":
                data["cmd_vel"].append((last_clock, msg.linear.x, msg.linear.y, msg.angular.z))
    return data


def perception_errors(data):
    """Per source, eval_recorder's figures (estimates paired with truth at their image stamps). A bag
    with no truth at all (a robot's) leaves detection rates and timings only; eval_recorder's warning
    per source that its estimates had no truth is then held back: the summary's missing list says it."""
    rec = EvalRecorder.__new__(EvalRecorder)  # its evaluate() only needs the truth table
    rec.truth = data["truth"]
    out, raw = {}, {}
    rospy_log = logging.getLogger("rosout")  # where rospy.logwarn writes
    level = rospy_log.level
    if not any(data["truth"].values()):
        rospy_log.setLevel(logging.ERROR)
    try:
        for name, estimates in data["estimates"].items():
            if estimates:
                out[name], raw[name] = rec.evaluate(name, estimates)
    finally:
        rospy_log.setLevel(level)
    return out, raw


def missing_from(data):
    """What the analysis lacks in this bag, as `what (topic)`: a robot bag has no truth, an older one
    may lack the arbiter status or the docking goal."""
    missing = [f"{TOPIC_CONTENTS[t]} ({t})" for t in TOPIC_CONTENTS if t not in data["topics"]]
    if "/tf" in data["topics"] and not has_truth_poses(data):
        missing.insert(0, f"{TOPIC_CONTENTS['/tf']} (/tf holds no world -> *_truth frames)")
    return missing


def has_truth_poses(data):
    return bool(data["chaser"].t and data["port"].t)


def run_span(data):
    """(start, end) of the run in bag time: the truth poses where the bag has them, else the planner's
    states, else the bag itself."""
    if has_truth_poses(data):
        return data["chaser"].t[0], data["chaser"].t[-1]
    if data["states"]:
        return data["states"][0].header.stamp.to_sec(), data["states"][-1].header.stamp.to_sec()
    return data["span"]


def analyze(bag_path, probe_x=None, timeout_s=None, require_truth=False):
    """The summary of one run. Without the simulator's truth (a robot bag) the docking errors are None
    and summary["missing"] says so; require_truth (a simulator run judged on it) makes that an error."""
    probe_x = probe_x_from_robot_yaml() if probe_x is None else probe_x
    data = read_bag(bag_path)
    states = data["states"]
    truth = has_truth_poses(data)
    if require_truth and not truth:
        raise RuntimeError(f"{bag_path}: no truth poses (world -> chaser_truth / target_truth) in the bag")
    if not data["topics"] or data["span"] is None:
        raise RuntimeError(f"{bag_path}: none of the topics this analysis reads: {', '.join(sorted(TOPIC_CONTENTS))}")
    start, end = run_span(data)
    # Time counts from the docking goal (the planner is IDLE before it), or from the start of the run.
    t0 = data["goal_times"][0] if data["goal_times"] else start
    docked_msg = next((s for s in states if s.state == DOCKED), None)
    t_end = docked_msg.header.stamp.to_sec() if docked_msg else end
    pos_err, yaw_err = (docking_errors(data["chaser"].at(t_end), data["port"].at(t_end), probe_x) if truth
                        else (None, None))

    state_tl = segments([(s.header.stamp.to_sec() - t0, s.state_name) for s in states])
    # Each state segment with the reason given when it opened.
    j = 0
    for seg in state_tl:
        while j < len(states) and states[j].header.stamp.to_sec() - t0 < seg["start_s"]:
            j += 1
        seg["reason"] = states[j].reason if j < len(states) else ""
    source_tl = segments([(s.header.stamp.to_sec() - t0,
                           SOURCE_NAMES[s.estimate_source] if (s.target_visible and s.estimate_source < 4) else "none")
                          for s in states])
    arbiter_tl = [{"t_s": t - t0, "status": text} for t, text in data["arbiter"]]
    source_time = {}
    for seg in source_tl:
        source_time[seg["value"]] = source_time.get(seg["value"], 0.0) + seg["end_s"] - seg["start_s"]
    perception, raw = perception_errors(data)
    last = docked_msg or (states[-1] if states else None)  # after DOCKED the planner goes IDLE
    visited = []
    for seg in state_tl:
        if not visited or visited[-1] != seg["value"]:
            visited.append(seg["value"])
    summary = {
        "bag": str(bag_path),
        "docked": docked_msg is not None,
        "time_to_dock_s": (t_end - t0) if docked_msg else None,
        "time_counted_from": "docking goal" if data["goal_times"] else "start of the run",
        "final_position_error_m": pos_err,
        "final_yaw_error_deg": yaw_err,
        "errors_at": "DOCKED" if docked_msg else "end of run",
        "sim_duration_s": end - t0,
        "t0_s": t0,
        "truth": truth,
        "missing": missing_from(data),
        "last_state": last.state_name if last else None,
        "last_reason": last.reason if last else "the planner never published docking/state",
        "states_visited": visited,
        "docked_on_odometry": bool(docked_msg and "odometry" in docked_msg.reason),
        "planner_estimated_errors_at_end": ({"position_m": None if last is None else math.hypot(
            last.lateral_error_m, last.axial_distance_m - probe_x), "yaw_deg": None if last is None else
            math.degrees(abs(last.yaw_error_rad))} if last else None),
        "state_timeline": state_tl,
        "source_timeline": source_tl,
        "source_time_s": source_time,
        "arbiter_status_timeline": arbiter_tl,
        "perception": perception,
        "probe_x_m": probe_x,
    }
    if timeout_s is not None and not docked_msg:
        summary["timeout_s"] = timeout_s
    return summary, data, raw


def plot(summary, data, raw, out_dir):
    """trajectory.png (needs the truth) and timeline.png (its truth panels only where the bag has it)."""
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    out_dir = pathlib.Path(out_dir)
    if summary["truth"]:
        plot_trajectory(plt, summary, data, out_dir)
    plot_timeline(plt, summary, data, raw, out_dir)


def plot_trajectory(plt, summary, data, out_dir):
    """Top-down: truth of both robots, safe circle around the port, planned paths (odom -> world)."""
    ch, po = data["chaser"], data["port"]
    t0 = ch.t[0]
    probe_x = summary["probe_x_m"]
    fig, ax = plt.subplots(figsize=(7, 7))
    ax.plot(ch.x, ch.y, "b-", label="chaser base_link (truth)")
    tips = [(x + probe_x * math.cos(a), y + probe_x * math.sin(a)) for x, y, a in zip(ch.x, ch.y, ch.yaw)]
    ax.plot([p[0] for p in tips], [p[1] for p in tips], "c-", lw=0.8, label="probe tip (truth)")
    ax.plot(po.x, po.y, "r-", label="docking port (truth)")
    step = max(1, len(po.t) // 12)
    for i in range(0, len(po.t), step):
        ax.arrow(po.x[i], po.y[i], 0.15 * math.cos(po.yaw[i]), 0.15 * math.sin(po.yaw[i]), color="r",
                 width=0.004, alpha=0.5)
    step = max(1, len(ch.t) // 20)
    for i in range(0, len(ch.t), step):
        ax.arrow(ch.x[i], ch.y[i], 0.12 * math.cos(ch.yaw[i]), 0.12 * math.sin(ch.yaw[i]), color="b",
                 width=0.003, alpha=0.5)
    t_end = (summary["time_to_dock_s"] + summary["t0_s"]) if summary["docked"] else ch.t[-1]
    pe = po.at(t_end)
    ax.add_patch(plt.Circle((pe[1], pe[2]), 0.6, fill=False, ls="--", color="k", label="safe circle (0.6 m), final"))
    pstart = po.at(t0)
    ax.add_patch(plt.Circle((pstart[1], pstart[2]), 0.6, fill=False, ls=":", color="grey", label="safe circle, start"))
    w2o = data["world_to_odom"]
    if w2o and data["paths"]:
        _, ox, oy, oyaw = w2o
        c, s = math.cos(oyaw), math.sin(oyaw)
        picks = data["paths"][:: max(1, len(data["paths"]) // 6)] + [data["paths"][-1]]
        for k, (_, pts) in enumerate(picks):
            if len(pts) < 2:
                continue
            wx = [ox + c * x - s * y for x, y in pts]
            wy = [oy + s * x + c * y for x, y in pts]
            ax.plot(wx, wy, "g-", lw=0.8, alpha=0.3 + 0.7 * (k + 1) / len(picks),
                    label="planned path (docking/path)" if k == 0 else None)
    ax.set_aspect("equal")
    ax.grid(True, alpha=0.3)
    ax.set_xlabel("world x [m]")
    ax.set_ylabel("world y [m]")
    ax.set_title("docked in %.1f s" % summary["time_to_dock_s"] if summary["docked"] else
                 "not docked: %s" % summary["last_state"])
    ax.legend(fontsize=7, loc="best")
    fig.tight_layout()
    fig.savefig(out_dir / "trajectory.png", dpi=100)
    plt.close(fig)


def plot_timeline(plt, summary, data, raw, out_dir):
    """Against time: range, errors (truth), planner state, source in use, and the estimates' errors
    against the truth at their stamps or, where the bag has none, the estimated ranges."""
    ch, po = data["chaser"], data["port"]
    truth = summary["truth"]
    t0 = ch.t[0] if truth else summary["t0_s"]
    probe_x = summary["probe_x_m"]
    panels = ["range"] + (["errors"] if truth else []) + ["state", "source", "estimates"]
    fig, axes = plt.subplots(len(panels), 1, figsize=(10, 2.2 * len(panels)), sharex=True)
    ax = dict(zip(panels, axes))
    st = data["states"]
    if truth:
        ts, rng, perr, yerr = [t - t0 for t in ch.t], [], [], []
        for t in ch.t:
            p = po.at(t)
            c = ch.at(t)
            e, y = docking_errors(c, p, probe_x)
            rng.append(math.hypot(c[1] - p[1], c[2] - p[2]))
            perr.append(e)
            yerr.append(y)
        ax["range"].plot(ts, rng, label="base_link to port (truth)")
        ax["range"].plot(ts, perr, label="probe tip to port (truth)")
        ax["errors"].semilogy(ts, [max(e, 1e-4) * 100 for e in perr], label="tip position error (truth) [cm]")
        ax["errors"].semilogy(ts, [max(y, 1e-3) for y in yerr], label="yaw error (truth) [deg]")
        ax["errors"].axhline(1.0, ls="--", color="k", lw=0.7)
        ax["errors"].set_ylabel("error")
        ax["errors"].legend(fontsize=7)
    ax["range"].plot([s.header.stamp.to_sec() - t0 for s in st], [s.range_m for s in st], ".", ms=1,
                     label="planner's range (estimated)")
    ax["range"].axhline(0.6, ls="--", color="k", lw=0.7)
    ax["range"].set_ylabel("range [m]")
    ax["range"].legend(fontsize=7)
    ax["state"].step([s.header.stamp.to_sec() - t0 for s in st], [s.state for s in st], where="post")
    ax["state"].set_yticks(range(len(STATE_NAMES)))
    ax["state"].set_yticklabels(STATE_NAMES, fontsize=7)
    ax["state"].set_ylabel("planner state")
    ax["source"].plot([s.header.stamp.to_sec() - t0 for s in st],
                      [s.estimate_source if s.target_visible else -1 for s in st], ".", ms=2)
    ax["source"].set_yticks([-1, 0, 1, 2])
    ax["source"].set_yticklabels(["none", "disparity", "mono_visible", "mono_ir"], fontsize=7)
    ax["source"].set_ylabel("source in use")
    errors = {name: [(x["t"] - t0, 100 * x["position_error"]) for x in samples if x["position_error"] is not None]
              for name, samples in raw.items()}
    if any(errors.values()):
        for name, pts in errors.items():
            if pts:
                ax["estimates"].semilogy([p[0] for p in pts], [max(p[1], 1e-2) for p in pts], ".", ms=2, label=name)
        ax["estimates"].set_ylabel("estimate error [cm]")
    else:
        for name, estimates in data["estimates"].items():
            pts = [(e.header.stamp.to_sec() - t0, e.range_m) for e in estimates if e.valid]
            if pts:
                ax["estimates"].plot([p[0] for p in pts], [p[1] for p in pts], ".", ms=2, label=name)
        ax["estimates"].set_ylabel("estimated range [m]")
    ax["estimates"].set_xlabel("sim time [s]" if truth else "time [s]")
    ax["estimates"].legend(fontsize=7)
    for a in axes:
        a.grid(True, alpha=0.3)
    fig.tight_layout()
    fig.savefig(out_dir / "timeline.png", dpi=90)
    plt.close(fig)


def print_summary(s, out=sys.stdout):
    w = out.write
    clock = "sim" if s["truth"] else "bag time"
    if s["docked"]:
        w("DOCKED in %.1f s (%s)%s\n" % (s["time_to_dock_s"], clock,
                                        ", finished on odometry" if s["docked_on_odometry"] else ""))
    else:
        w("NOT DOCKED after %.1f s (%s): last state %s: %s\n" % (s["sim_duration_s"], clock, s["last_state"],
                                                               s["last_reason"]))
    if s["truth"]:
        w("  final error (truth, %s): probe tip %.1f mm, yaw %.2f deg  (goal: 10 mm, 1 deg)\n"
          % (s["errors_at"], 1000 * s["final_position_error_m"], s["final_yaw_error_deg"]))
    else:
        w("  final error: not measured, the bag holds no truth (a robot bag; the simulator's bag:= has it)\n")
    w("  states: %s\n" % " -> ".join(s["states_visited"]))
    for seg in s["state_timeline"]:
        w("    %6.1f-%6.1f s  %-8s %s\n" % (seg["start_s"], seg["end_s"], seg["value"], seg["reason"][:90]))
    w("  source in use (planner's view):\n")
    for seg in s["source_timeline"]:
        w("    %6.1f-%6.1f s  %s\n" % (seg["start_s"], seg["end_s"], seg["value"]))
    w("  perception against truth at the image stamps:\n" if any(
        v["position_error_median_m"] is not None for v in s["perception"].values()) else
      "  perception (no truth at the image stamps: detection rates only):\n")
    for name, v in s["perception"].items():
        def f(x, scale=1.0, fmt="%.1f"):
            return "-" if x is None else fmt % (x * scale)
        w("    %-13s %5d frames, detection %.2f, position median %s cm / p95 %s cm, orientation median %s deg\n"
          % (name, v["frames"], v["detection_rate"], f(v["position_error_median_m"], 100),
             f(v["position_error_p95_m"], 100), f(v["orientation_error_median_deg"])))
    if s["missing"]:
        w("  not in this bag:\n")
        for what in s["missing"]:
            w("    %s\n" % what)


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("bag")
    ap.add_argument("out_dir")
    ap.add_argument("--probe-x", type=float, default=None)
    a = ap.parse_args()
    try:
        s, data, raw = analyze(a.bag, a.probe_x)
    except RuntimeError as e:
        sys.exit(f"analyze_run: {e}")
    pathlib.Path(a.out_dir).mkdir(parents=True, exist_ok=True)
    plot(s, data, raw, a.out_dir)
    with open(pathlib.Path(a.out_dir) / "summary.json", "w") as f:
        json.dump(s, f, indent=2)
    print_summary(s)


if __name__ == "__main__":
    main()
