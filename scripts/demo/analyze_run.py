#!/usr/bin/env python3
"""Analysis of one closed-loop simulator run from its bag (launch/sim.launch bag:=...): the outcome
measured against the simulator's TRUTH, the planner's state timeline, the arbiter's source timeline,
the perception error per source (scripts/eval/eval_recorder.py's pairing of estimates with truth at
their stamps, reused), and PNG plots. Used by scripts/demo/run_demo.py and scripts/demo/run_campaign.py;
standalone:  analyze_run.py RUN.bag OUT_DIR [--probe-x 0.18]
"""
import argparse
import bisect
import json
import math
import pathlib
import sys

ROOT = pathlib.Path(__file__).resolve().parents[2]
sys.path.insert(0, str(ROOT / "scripts" / "eval"))
from eval_recorder import EvalRecorder, SOURCES, TRUTH_TOPICS  # noqa: E402  (reused, not copied)

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


def read_bag(bag_path):
    import rosbag
    data = {"chaser": Series(), "port": Series(), "states": [], "arbiter": [], "paths": [],
            "truth": {frame: {} for frame in TRUTH_TOPICS}, "estimates": {n: [] for n in SOURCES},
            "world_to_odom": None, "cmd_vel": [], "goal_times": []}
    truth_topic_frame = {topic: frame for frame, topic in TRUTH_TOPICS.items()}
    source_topic = {topic: name for name, topic in SOURCES.items()}
    last_clock = None
    with rosbag.Bag(str(bag_path)) as bag:
        for topic, msg, t in bag.read_messages():
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
    """Per source, eval_recorder's figures (estimates paired with truth at their image stamps)."""
    rec = EvalRecorder.__new__(EvalRecorder)  # its evaluate() only needs the truth table
    rec.truth = data["truth"]
    out, raw = {}, {}
    for name, estimates in data["estimates"].items():
        if estimates:
            out[name], raw[name] = rec.evaluate(name, estimates)
    return out, raw


def analyze(bag_path, probe_x=None, timeout_s=None):
    probe_x = probe_x_from_robot_yaml() if probe_x is None else probe_x
    data = read_bag(bag_path)
    states = data["states"]
    if not data["chaser"].t or not data["port"].t:
        raise RuntimeError(f"{bag_path}: no truth poses (world -> chaser_truth / target_truth) in the bag")
    # Time counts from the docking goal (the planner is IDLE before it), or from the start of the run.
    t0 = data["goal_times"][0] if data["goal_times"] else data["chaser"].t[0]
    docked_msg = next((s for s in states if s.state == DOCKED), None)
    t_end = docked_msg.header.stamp.to_sec() if docked_msg else data["chaser"].t[-1]
    pos_err, yaw_err = docking_errors(data["chaser"].at(t_end), data["port"].at(t_end), probe_x)

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
        "sim_duration_s": data["chaser"].t[-1] - t0,
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
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    out_dir = pathlib.Path(out_dir)
    ch, po = data["chaser"], data["port"]
    t0 = ch.t[0]
    probe_x = summary["probe_x_m"]

    # Top-down: truth of both robots, safe circle around the port, planned paths (odom -> world).
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
    t_end = (summary["time_to_dock_s"] + t0) if summary["docked"] else ch.t[-1]
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

    # Against time: range, errors (truth), planner state, source in use, perception error.
    ts = [t - t0 for t in ch.t]
    rng, perr, yerr = [], [], []
    for t in ch.t:
        p = po.at(t)
        c = ch.at(t)
        e, y = docking_errors(c, p, probe_x)
        rng.append(math.hypot(c[1] - p[1], c[2] - p[2]))
        perr.append(e)
        yerr.append(y)
    fig, axes = plt.subplots(5, 1, figsize=(10, 11), sharex=True)
    axes[0].plot(ts, rng, label="base_link to port (truth)")
    axes[0].plot(ts, perr, label="probe tip to port (truth)")
    st = data["states"]
    axes[0].plot([s.header.stamp.to_sec() - t0 for s in st], [s.range_m for s in st], ".", ms=1,
                 label="planner's range (estimated)")
    axes[0].axhline(0.6, ls="--", color="k", lw=0.7)
    axes[0].set_ylabel("range [m]")
    axes[0].legend(fontsize=7)
    axes[1].semilogy(ts, [max(e, 1e-4) * 100 for e in perr], label="tip position error (truth) [cm]")
    axes[1].semilogy(ts, [max(y, 1e-3) for y in yerr], label="yaw error (truth) [deg]")
    axes[1].axhline(1.0, ls="--", color="k", lw=0.7)
    axes[1].set_ylabel("error")
    axes[1].legend(fontsize=7)
    axes[2].step([s.header.stamp.to_sec() - t0 for s in st], [s.state for s in st], where="post")
    axes[2].set_yticks(range(len(STATE_NAMES)))
    axes[2].set_yticklabels(STATE_NAMES, fontsize=7)
    axes[2].set_ylabel("planner state")
    axes[3].plot([s.header.stamp.to_sec() - t0 for s in st],
                 [s.estimate_source if s.target_visible else -1 for s in st], ".", ms=2)
    axes[3].set_yticks([-1, 0, 1, 2])
    axes[3].set_yticklabels(["none", "disparity", "mono_visible", "mono_ir"], fontsize=7)
    axes[3].set_ylabel("source in use")
    for name, samples in raw.items():
        pts = [(x["t"] - t0, 100 * x["position_error"]) for x in samples if x["position_error"] is not None]
        if pts:
            axes[4].semilogy([p[0] for p in pts], [max(p[1], 1e-2) for p in pts], ".", ms=2, label=name)
    axes[4].set_ylabel("estimate error [cm]")
    axes[4].set_xlabel("sim time [s]")
    axes[4].legend(fontsize=7)
    for a in axes:
        a.grid(True, alpha=0.3)
    fig.tight_layout()
    fig.savefig(out_dir / "timeline.png", dpi=90)
    plt.close(fig)


def print_summary(s, out=sys.stdout):
    w = out.write
    if s["docked"]:
        w("DOCKED in %.1f s (sim)%s\n" % (s["time_to_dock_s"], ", finished on odometry" if s["docked_on_odometry"] else ""))
    else:
        w("NOT DOCKED after %.1f s (sim): last state %s: %s\n" % (s["sim_duration_s"], s["last_state"], s["last_reason"]))
    w("  final error (truth, %s): probe tip %.1f mm, yaw %.2f deg  (goal: 10 mm, 1 deg)\n"
      % (s["errors_at"], 1000 * s["final_position_error_m"], s["final_yaw_error_deg"]))
    w("  states: %s\n" % " -> ".join(s["states_visited"]))
    for seg in s["state_timeline"]:
        w("    %6.1f-%6.1f s  %-8s %s\n" % (seg["start_s"], seg["end_s"], seg["value"], seg["reason"][:90]))
    w("  source in use (planner's view):\n")
    for seg in s["source_timeline"]:
        w("    %6.1f-%6.1f s  %s\n" % (seg["start_s"], seg["end_s"], seg["value"]))
    w("  perception against truth at the image stamps:\n")
    for name, v in s["perception"].items():
        def f(x, scale=1.0, fmt="%.1f"):
            return "-" if x is None else fmt % (x * scale)
        w("    %-13s %5d frames, detection %.2f, position median %s cm / p95 %s cm, orientation median %s deg\n"
          % (name, v["frames"], v["detection_rate"], f(v["position_error_median_m"], 100),
             f(v["position_error_p95_m"], 100), f(v["orientation_error_median_deg"])))


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("bag")
    ap.add_argument("out_dir")
    ap.add_argument("--probe-x", type=float, default=None)
    a = ap.parse_args()
    s, data, raw = analyze(a.bag, a.probe_x)
    pathlib.Path(a.out_dir).mkdir(parents=True, exist_ok=True)
    plot(s, data, raw, a.out_dir)
    with open(pathlib.Path(a.out_dir) / "summary.json", "w") as f:
        json.dump(s, f, indent=2)
    print_summary(s)


if __name__ == "__main__":
    main()
