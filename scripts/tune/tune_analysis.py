"""The analysis half of the tuning tool (scripts/tune/tune_replay.py, issue 13): from the bag that was
replayed and the bags the replays recorded, per source (the three estimators and the arbiter's fused
output):
  - detection rate: frames with a valid estimate / image frames of that source's camera in the bag (the
    disparity detector: the stereo pairs);
  - error against the simulator's truth, where the bag holds it;
  - CPU time per frame (the estimators' own processing_time_ms);
  - differences between two configurations, stamp by stamp.
No ROS graph is needed: rosbag reads the files. Kept apart from the replay runner so that a test can
check the numbers on a bag it writes itself with known estimates and truth.

Frames. An estimate is a pose of the `target` frame in its header.frame_id (the estimators: their
camera's optical frame; the arbiter: its output_frame, stereo_left_optical_frame). The simulator's truth
topics give the port in one camera's optical frame each, at that camera's stamps. An estimate is
compared with the truth of the frame its header names; when there is no truth in that frame at that
stamp (the fused output of an IR estimate where the cameras are not synchronised, or another output
frame), a truth of another camera at the same stamp is carried over through the static camera frames
of the recorded bag's /tf_static (the frames the simulator rendered with). Stamps must match exactly:
truth is published at every camera stamp, so nothing is interpolated.
"""
import dataclasses
import math

import numpy as np
import rosbag

# source name -> (estimate topic, the camera whose frames it answers; None: every camera's frames).
# "stereo pairs": the left frames whose right image the bag holds too (all of them in a bag without right
# camera frames): a live docking's right camera runs at the block matcher's rate only.
SOURCES = {
    "disparity": ("/perception/disparity/estimate", "stereo pairs"),
    "mono_visible": ("/perception/mono_visible/estimate", "stereo/left"),
    "mono_ir": ("/perception/mono_ir/estimate", "ir"),
    "fused": ("/target/estimate", None),
}
CAMERAS = ("stereo/left", "ir")
TRUTH_TOPICS = ("sim/truth/stereo_left", "sim/truth/ir")
# The arbiter's output copies the chosen estimator's processing_time_ms: not a cost of its own.
CPU_SOURCES = ("disparity", "mono_visible", "mono_ir")


@dataclasses.dataclass
class Pose:
    """A rigid transform: position (m) and unit quaternion (x, y, z, w), of a child frame in a parent."""
    position: np.ndarray
    quaternion: np.ndarray

    def rotation(self):
        x, y, z, w = self.quaternion
        return np.array([[1 - 2 * (y * y + z * z), 2 * (x * y - z * w), 2 * (x * z + y * w)],
                         [2 * (x * y + z * w), 1 - 2 * (x * x + z * z), 2 * (y * z - x * w)],
                         [2 * (x * z - y * w), 2 * (y * z + x * w), 1 - 2 * (x * x + y * y)]])

    def compose(self, other):
        """self * other: other's child expressed in self's parent."""
        return Pose(self.position + self.rotation() @ other.position,
                    quaternion_multiply(self.quaternion, other.quaternion))

    def inverse(self):
        conjugate = np.array([-self.quaternion[0], -self.quaternion[1], -self.quaternion[2], self.quaternion[3]])
        inverse = Pose(np.zeros(3), conjugate)
        inverse.position = -(inverse.rotation() @ self.position)
        return inverse


@dataclasses.dataclass
class Estimate:
    """What the analysis needs of one TargetEstimate."""
    frame_id: str
    valid: bool
    position_valid: bool
    orientation_valid: bool
    pose: Pose
    range_m: float
    processing_time_ms: float


def quaternion_multiply(a, b):
    ax, ay, az, aw = a
    bx, by, bz, bw = b
    return np.array([aw * bx + ax * bw + ay * bz - az * by,
                     aw * by - ax * bz + ay * bw + az * bx,
                     aw * bz + ax * by - ay * bx + az * bw,
                     aw * bw - ax * bx - ay * by - az * bz])


def angle_between_deg(qa, qb):
    """The angle of the rotation that takes one orientation to the other (q and -q are one rotation)."""
    dot = abs(float(np.dot(qa, qb))) / (np.linalg.norm(qa) * np.linalg.norm(qb))
    return math.degrees(2.0 * math.acos(min(1.0, dot)))


def pose_of(msg_pose):
    p, q = msg_pose.position, msg_pose.orientation
    return Pose(np.array([p.x, p.y, p.z]), np.array([q.x, q.y, q.z, q.w]))


def name_of(topic):
    """Bags from record.launch use absolute names, older ones relative: both compare equal stripped."""
    return topic.strip("/")


def read_camera_frames(bag_path):
    """camera -> sorted image stamps (ns) of the bag. camera_info (small; one per image, same stamp)
    is read when the bag has it, the images otherwise."""
    frames = {camera: set() for camera in CAMERAS}
    with rosbag.Bag(bag_path) as bag:
        names = {name_of(t): t for t in bag.get_type_and_topic_info().topics}
        for camera in CAMERAS:
            wanted = camera + "/camera_info" if camera + "/camera_info" in names else camera + "/image_raw"
            if wanted not in names:
                continue
            for _, msg, _ in bag.read_messages(topics=[names[wanted]]):
                frames[camera].add(msg.header.stamp.to_nsec())
        right = "stereo/right/camera_info" if "stereo/right/camera_info" in names else "stereo/right/image_raw"
        if right in names:
            right_stamps = {msg.header.stamp.to_nsec() for _, msg, _ in bag.read_messages(topics=[names[right]])}
            frames["stereo pairs"] = frames["stereo/left"] & right_stamps
    return {camera: sorted(stamps) for camera, stamps in frames.items()}


def read_truth(bag_path):
    """stamp ns -> {frame_id: Pose of the port in that camera frame}, from the simulator's truth
    topics; empty for a bag from the robot."""
    truth = {}
    with rosbag.Bag(bag_path) as bag:
        topics = [t for t in bag.get_type_and_topic_info().topics if name_of(t) in TRUTH_TOPICS]
        for _, msg, _ in bag.read_messages(topics=topics):
            truth.setdefault(msg.header.stamp.to_nsec(), {})[msg.header.frame_id] = pose_of(msg.pose.pose)
    return truth


def read_static_frames(bag_path):
    """child frame -> (parent frame, Pose of the child in the parent), from the bag's /tf_static."""
    frames = {}
    with rosbag.Bag(bag_path) as bag:
        topics = [t for t in bag.get_type_and_topic_info().topics if name_of(t) == "tf_static"]
        for _, msg, _ in bag.read_messages(topics=topics):
            for transform in msg.transforms:
                t, q = transform.transform.translation, transform.transform.rotation
                frames[transform.child_frame_id] = (transform.header.frame_id,
                                                    Pose(np.array([t.x, t.y, t.z]), np.array([q.x, q.y, q.z, q.w])))
    return frames


def read_estimates(bag_path):
    """source -> {stamp ns: Estimate}, and source -> number of stamps answered more than once.
    A stamp with several messages keeps a valid one (the arbiter re-publishes "nothing valid" stamped
    with the current time, which can coincide with a frame's stamp)."""
    topic_to_source = {name_of(topic): source for source, (topic, _) in SOURCES.items()}
    estimates = {source: {} for source in SOURCES}
    repeated = {source: 0 for source in SOURCES}
    with rosbag.Bag(bag_path) as bag:
        topics = [t for t in bag.get_type_and_topic_info().topics if name_of(t) in topic_to_source]
        for topic, msg, _ in bag.read_messages(topics=topics):
            source = topic_to_source[name_of(topic)]
            stamp = msg.header.stamp.to_nsec()
            estimate = Estimate(msg.header.frame_id, bool(msg.valid), bool(msg.valid and msg.position_valid),
                                bool(msg.valid and msg.orientation_valid), pose_of(msg.pose.pose),
                                float(msg.range_m), float(msg.processing_time_ms))
            earlier = estimates[source].get(stamp)
            if earlier is not None:
                repeated[source] += 1
                if earlier.valid and not estimate.valid:
                    continue
            estimates[source][stamp] = estimate
    return estimates, repeated


def pose_in_root(frame, static_frames):
    """(root frame, Pose of `frame` in it), following the static parents up."""
    pose = Pose(np.zeros(3), np.array([0.0, 0.0, 0.0, 1.0]))
    seen = set()
    while frame in static_frames and frame not in seen:
        seen.add(frame)
        parent, child_in_parent = static_frames[frame]
        pose = child_in_parent.compose(pose)
        frame = parent
    return frame, pose


def truth_for(frame_id, stamp, truth, static_frames):
    """The port's true Pose in frame_id at stamp: the truth of that frame, or another camera's truth at
    the same stamp carried over through the static frames; None when neither exists."""
    at_stamp = truth.get(stamp, {})
    if frame_id in at_stamp:
        return at_stamp[frame_id]
    root, wanted_in_root = pose_in_root(frame_id, static_frames)
    for other_frame, port_in_other in sorted(at_stamp.items()):
        other_root, other_in_root = pose_in_root(other_frame, static_frames)
        if other_root == root:
            return wanted_in_root.inverse().compose(other_in_root).compose(port_in_other)
    return None


def statistics_of(values, scale=1.0):
    """{'median', 'p95', 'n'} of a list (numpy's linear-interpolation percentiles); None values when
    the list is empty, so that a JSON reader sees 'not measured' rather than a zero."""
    if not values:
        return {"median": None, "p95": None, "n": 0}
    array = np.asarray(values, dtype=float) * scale
    return {"median": float(np.median(array)), "p95": float(np.percentile(array, 95)), "n": len(values)}


def frames_of(source, camera_frames):
    """The frame stamps a source answers: its camera's, or for the fused output every camera's."""
    camera = SOURCES[source][1]
    if camera == "stereo pairs" and camera not in camera_frames:
        camera = "stereo/left"
    if camera is not None:
        return camera_frames.get(camera, [])
    return sorted(set().union(*camera_frames.values())) if camera_frames else []


def truth_errors(estimates, truth, static_frames):
    """Position (m), signed range (m) and orientation (deg) errors of the valid estimates that have a
    truth, and how many valid ones had none."""
    position, range_signed, orientation, unmatched = [], [], [], 0
    for stamp, estimate in sorted(estimates.items()):
        if not estimate.position_valid:
            continue
        true_pose = truth_for(estimate.frame_id, stamp, truth, static_frames)
        if true_pose is None:
            unmatched += 1
            continue
        position.append(float(np.linalg.norm(estimate.pose.position - true_pose.position)))
        range_signed.append(estimate.range_m - float(np.linalg.norm(true_pose.position)))
        if estimate.orientation_valid:
            orientation.append(angle_between_deg(estimate.pose.quaternion, true_pose.quaternion))
    return position, range_signed, orientation, unmatched


def source_metrics(source, estimates, camera_frames, truth, static_frames):
    """One source's numbers for one configuration (see the module docstring)."""
    frames = frames_of(source, camera_frames)
    valid_frames = sum(1 for stamp in frames if stamp in estimates and estimates[stamp].valid)
    answered = sum(1 for stamp in frames if stamp in estimates)
    metrics = {
        "frames": len(frames),
        "answered_frames": answered,
        "valid_frames": valid_frames,
        "detection_rate": valid_frames / len(frames) if frames else None,
    }
    if truth:
        position, range_signed, orientation, unmatched = truth_errors(estimates, truth, static_frames)
        metrics["position_error_mm"] = statistics_of(position, 1000.0)
        metrics["range_error_mm"] = statistics_of([abs(r) for r in range_signed], 1000.0)
        metrics["range_bias_mm"] = float(np.median(range_signed)) * 1000.0 if range_signed else None
        metrics["orientation_error_deg"] = statistics_of(orientation)
        metrics["valid_without_truth"] = unmatched
    if source in CPU_SOURCES:
        frame_set = set(frames)
        metrics["cpu_ms"] = statistics_of([e.processing_time_ms for s, e in estimates.items() if s in frame_set])
    return metrics


def differences(reference, other, frames):
    """Stamp-by-stamp differences of one source between two configurations, over its frames: position
    (m) and orientation (deg) where both claim them, and the frames valid in one and not the other."""
    position, orientation = [], []
    lost, gained = 0, 0
    for stamp in frames:
        a, b = reference.get(stamp), other.get(stamp)
        valid_a, valid_b = bool(a and a.valid), bool(b and b.valid)
        lost += valid_a and not valid_b
        gained += valid_b and not valid_a
        if a and b and a.position_valid and b.position_valid:
            position.append(float(np.linalg.norm(a.pose.position - b.pose.position)))
        if a and b and a.orientation_valid and b.orientation_valid:
            orientation.append(angle_between_deg(a.pose.quaternion, b.pose.quaternion))
    return {
        "position_mm": statistics_of(position, 1000.0),
        "orientation_deg": statistics_of(orientation),
        "validity_flips": lost + gained,
        "valid_only_in_reference": lost,
        "valid_only_in_this": gained,
    }


def analyse(input_bag, output_bags):
    """The report's numbers: one entry per configuration (its output bag), the first the reference.
    Returns {"truth": bool, "frames": {camera: n}, "configurations": [{source: metrics}, ...]}."""
    camera_frames = read_camera_frames(input_bag)
    truth = read_truth(input_bag)
    static_frames = read_static_frames(input_bag)
    runs = [read_estimates(path) for path in output_bags]
    reference = runs[0][0]
    results = []
    for estimates, repeated in runs:
        per_source = {}
        for source in SOURCES:
            metrics = source_metrics(source, estimates[source], camera_frames, truth, static_frames)
            metrics["repeated_stamps"] = repeated[source]
            metrics["difference_to_reference"] = differences(reference[source], estimates[source],
                                                             frames_of(source, camera_frames))
            per_source[source] = metrics
        results.append(per_source)
    return {"truth": bool(truth), "frames": {c: len(s) for c, s in camera_frames.items()},
            "configurations": results}
