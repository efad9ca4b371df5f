"""Per source, how good the estimates of a replay are against the simulator's truth recorded in the input
bag: detection, confidently wrong estimates, 3-sigma coverage, errors and CPU (make ablate). The truth
pairing is tune_analysis's (same stamp, carried between cameras through the static frames); the measures
are estimate_quality's (the same as make eval's)."""
import math
import pathlib
import sys

import numpy as np
import rosbag

ROOT = pathlib.Path(__file__).resolve().parents[2]
sys.path.insert(0, str(ROOT / "scripts" / "tune"))
sys.path.insert(0, str(ROOT / "scripts" / "eval"))
import estimate_quality  # noqa: E402
import tune_analysis  # noqa: E402


def read_estimates(bag_path):
    """source -> {stamp ns: message}: one per stamp, a valid one kept over an invalid one."""
    topic_to_source = {tune_analysis.name_of(topic): source for source, (topic, _) in tune_analysis.SOURCES.items()}
    estimates = {source: {} for source in tune_analysis.SOURCES}
    with rosbag.Bag(str(bag_path)) as bag:
        topics = [t for t in bag.get_type_and_topic_info().topics if tune_analysis.name_of(t) in topic_to_source]
        for topic, msg, _ in bag.read_messages(topics=topics):
            source = topic_to_source[tune_analysis.name_of(topic)]
            stamp = msg.header.stamp.to_nsec()
            earlier = estimates[source].get(stamp)
            if earlier is not None and earlier.valid and not msg.valid:
                continue
            estimates[source][stamp] = msg
    return estimates


def judge(msg, true_pose):
    """(position error m, true range m, orientation error deg or None, normalized errors per axis)."""
    p = msg.pose.pose.position
    q = msg.pose.pose.orientation
    position_error = np.array([p.x, p.y, p.z]) - true_pose.position
    rotation = None
    orientation_error = None
    if msg.orientation_valid:
        q_est, q_true = (q.x, q.y, q.z, q.w), tuple(true_pose.quaternion)
        rotation = estimate_quality.rotation_error_vector(q_est, q_true)
        orientation_error = estimate_quality.rotation_angle_deg(q_est, q_true)
    normalized = estimate_quality.normalized_errors(position_error, rotation, [msg.pose.covariance[7 * i] for i in range(6)])
    return float(np.linalg.norm(position_error)), float(np.linalg.norm(true_pose.position)), orientation_error, normalized


def source_quality(source, estimates, frames, truth, static_frames):
    valid = [(stamp, estimates[stamp]) for stamp in frames if stamp in estimates and estimates[stamp].valid
             and estimates[stamp].position_valid]
    positions, orientations, cpu = [], [], []
    normalized = {axis: [] for axis in estimate_quality.AXES}
    wrong = 0
    for stamp, msg in valid:
        true_pose = tune_analysis.truth_for(msg.header.frame_id, stamp, truth, static_frames)
        if true_pose is None:
            continue
        position_error, true_range, orientation_error, z = judge(msg, true_pose)
        positions.append(position_error / true_range)
        if orientation_error is not None:
            orientations.append(orientation_error)
        wrong += int(estimate_quality.confidently_wrong(position_error, true_range, orientation_error))
        for axis, value in zip(estimate_quality.AXES, z):
            if value is not None:
                normalized[axis].append(value)
    cpu = [estimates[s].processing_time_ms for s in frames if s in estimates]
    coverage = estimate_quality.within_3_sigma(normalized)
    claimed = [v for v in coverage.values() if v is not None]
    return {
        "frames": len(frames),
        "valid": len(valid),
        "confident_wrong": wrong,
        "lowest_3_sigma": min(claimed) if claimed else None,
        "position_error_pct_median": 100.0 * float(np.median(positions)) if positions else None,
        "orientation_error_deg_median": float(np.median(orientations)) if orientations else None,
        "cpu_ms_median": float(np.median(cpu)) if cpu else None,
    }


def replay_quality(input_bag, output_bag):
    """source -> quality, for one replay of one held-out bag."""
    camera_frames = tune_analysis.read_camera_frames(str(input_bag))
    truth = tune_analysis.read_truth(str(input_bag))
    static_frames = tune_analysis.read_static_frames(str(input_bag))
    estimates = read_estimates(output_bag)
    return {source: source_quality(source, estimates[source], tune_analysis.frames_of(source, camera_frames), truth,
                                   static_frames)
            for source in tune_analysis.SOURCES}


def pooled(per_bag):
    """Sums and frame-weighted medians over bags: source -> quality."""
    out = {}
    for source in tune_analysis.SOURCES:
        rows = [bag[source] for bag in per_bag if source in bag]
        frames = sum(r["frames"] for r in rows)
        valid = sum(r["valid"] for r in rows)
        coverages = [r["lowest_3_sigma"] for r in rows if r["lowest_3_sigma"] is not None]

        def weighted(key):
            pairs = [(r[key], r["valid"]) for r in rows if r[key] is not None and r["valid"]]
            total = sum(w for _, w in pairs)
            return sum(v * w for v, w in pairs) / total if total else None
        out[source] = {"frames": frames, "valid": valid, "detection": valid / frames if frames else None,
                       "confident_wrong": sum(r["confident_wrong"] for r in rows),
                       "lowest_3_sigma": min(coverages) if coverages else None,
                       "position_error_pct": weighted("position_error_pct_median"),
                       "orientation_error_deg": weighted("orientation_error_deg_median"),
                       "cpu_ms": weighted("cpu_ms_median")}
    return out
