#!/usr/bin/env python3
"""Evaluation recorder: a ROS node that pairs every target estimate with the simulator's ground truth
at the same image stamp, for one scenario, and writes that scenario's entry of results/eval/summary.json
(plus the raw samples for plots). It shuts the launch down (it is `required`) when done.

Parameters (private): output (json path), scenario, lighting, warmup_s and duration_s (sim time),
range_m (optional: the nominal range; by default the true range at the first truth message).
"""
import json
import math
import statistics
import time

import rospy
from docking_msgs.msg import TargetEstimate
from nav_msgs.msg import Odometry

import estimate_quality
from estimate_quality import AXES, NOT_ESTIMATED_VARIANCE, WRONG_ORIENTATION_DEG, WRONG_POSITION_FRACTION_OF_RANGE  # noqa: F401

SOURCES = {  # summary key -> topic
    "disparity": "/perception/disparity/estimate",
    "mono_visible": "/perception/mono_visible/estimate",
    "mono_ir": "/perception/mono_ir/estimate",
    "fused": "/target/estimate",
}
TRUTH_TOPICS = {"stereo_left_optical_frame": "/sim/truth/stereo_left", "ir_optical_frame": "/sim/truth/ir"}


def rotation_angle_deg(qa, qb):
    """Angle of the rotation between two orientations (geometry_msgs quaternions)."""
    return estimate_quality.rotation_angle_deg(xyzw(qa), xyzw(qb))


def xyzw(q):
    return (q.x, q.y, q.z, q.w)


def normalized_errors(est, truth):
    """Per axis (x, y, z, rx, ry, rz): error / sigma from the estimate's covariance, None for an axis
    the estimate does not claim (invalid part or variance >= 1e6)."""
    pe, pt = est.pose.pose.position, truth.pose.pose.position
    rotation = (estimate_quality.rotation_error_vector(xyzw(est.pose.pose.orientation), xyzw(truth.pose.pose.orientation))
                if est.orientation_valid else None)
    return estimate_quality.normalized_errors((pe.x - pt.x, pe.y - pt.y, pe.z - pt.z), rotation,
                                              [est.pose.covariance[7 * i] for i in range(6)])


def percentile(values, p):
    if not values:
        return None
    s = sorted(values)
    k = (len(s) - 1) * p / 100.0
    lo, hi = math.floor(k), math.ceil(k)
    return s[lo] + (s[hi] - s[lo]) * (k - lo)


def median(values):
    return statistics.median(values) if values else None


class EvalRecorder:
    def __init__(self):
        self.output = rospy.get_param("~output")
        self.scenario = rospy.get_param("~scenario")
        self.lighting = rospy.get_param("~lighting", "nominal")
        self.warmup = rospy.get_param("~warmup_s", 3.0)
        self.duration = rospy.get_param("~duration_s", 10.0)
        self.nominal_range = rospy.get_param("~range_m", None)
        self.truth = {frame: {} for frame in TRUTH_TOPICS}  # frame -> {stamp_ns: Odometry}
        self.estimates = {name: [] for name in SOURCES}     # name -> [TargetEstimate]
        self.first_truth_range = None
        self.start = None
        for frame, topic in TRUTH_TOPICS.items():
            rospy.Subscriber(topic, Odometry, self.on_truth, callback_args=frame, queue_size=100)
        for name, topic in SOURCES.items():
            rospy.Subscriber(topic, TargetEstimate, self.on_estimate, callback_args=name, queue_size=100)

    def on_truth(self, msg, frame):
        self.truth[frame][msg.header.stamp.to_nsec()] = msg
        if self.first_truth_range is None and frame == "stereo_left_optical_frame":
            p = msg.pose.pose.position
            self.first_truth_range = math.sqrt(p.x ** 2 + p.y ** 2 + p.z ** 2)

    def on_estimate(self, msg, name):
        if self.start is None or msg.header.stamp.to_sec() < self.start + self.warmup:
            return
        self.estimates[name].append(msg)

    def run(self):
        while not rospy.is_shutdown() and rospy.get_time() == 0.0:
            time.sleep(0.05)  # wait for /clock
        self.start = rospy.get_time()
        end = self.start + self.warmup + self.duration
        wall_deadline = time.time() + 30.0 * (self.warmup + self.duration) + 60.0
        while not rospy.is_shutdown() and rospy.get_time() < end and time.time() < wall_deadline:
            time.sleep(0.05)
        time.sleep(1.0)  # let the last estimates of the window arrive
        self.write()

    def evaluate(self, name, estimates):
        samples = []
        for est in estimates:
            truth = self.truth.get(est.header.frame_id, {}).get(est.header.stamp.to_nsec())
            samples.append((est, truth))
        frames = len(samples)
        valid = [(e, t) for e, t in samples if e.valid and e.position_valid]
        pos_err, range_err, ori_err, lin_err, ang_err, proc = [], [], [], [], [], []
        normalized = {axis: [] for axis in AXES}
        confident_wrong = 0
        unmatched = 0
        for est, truth in valid:
            if truth is None:
                unmatched += 1
                continue
            pe, pt = est.pose.pose.position, truth.pose.pose.position
            pos_err.append(math.dist((pe.x, pe.y, pe.z), (pt.x, pt.y, pt.z)))
            true_range = math.sqrt(pt.x ** 2 + pt.y ** 2 + pt.z ** 2)
            est_range = math.sqrt(pe.x ** 2 + pe.y ** 2 + pe.z ** 2)
            range_err.append(100.0 * abs(est_range - true_range) / true_range)
            orientation_error = None
            if est.orientation_valid:
                orientation_error = rotation_angle_deg(est.pose.pose.orientation, truth.pose.pose.orientation)
                ori_err.append(orientation_error)
            confident_wrong += int(estimate_quality.confidently_wrong(pos_err[-1], true_range, orientation_error))
            for axis, z in zip(AXES, normalized_errors(est, truth)):
                if z is not None:
                    normalized[axis].append(z)
            if est.twist_valid:
                le, lt = est.twist.twist.linear, truth.twist.twist.linear
                ae, at = est.twist.twist.angular, truth.twist.twist.angular
                lin_err.append(math.dist((le.x, le.y, le.z), (lt.x, lt.y, lt.z)))
                ang_err.append(math.degrees(math.dist((ae.x, ae.y, ae.z), (at.x, at.y, at.z))))
        for est, _ in samples:
            proc.append(est.processing_time_ms)
        stamps = [e.header.stamp.to_sec() for e, _ in samples]
        span = (max(stamps) - min(stamps)) if len(stamps) > 1 else 0.0
        entry = {
            "frames": frames,
            "detection_rate": (len(valid) / frames) if frames else 0.0,
            "position_error_median_m": median(pos_err),
            "position_error_p95_m": percentile(pos_err, 95),
            "range_error_median_pct": median(range_err),
            "orientation_error_median_deg": median(ori_err),
            "orientation_error_p95_deg": percentile(ori_err, 95),
            "linear_velocity_error_median_mps": median(lin_err),
            "angular_velocity_error_median_dps": median(ang_err),
            "rate_hz": ((frames - 1) / span) if span > 0 else 0.0,
            "processing_ms_median": median(proc),
            # Issue 11: valid estimates off by > 5 % of range or > 10 deg, and the share of errors within
            # 3 sigma of the estimate's own covariance, per axis it claims (None: no such estimate).
            "confident_wrong": confident_wrong,
            "within_3_sigma": estimate_quality.within_3_sigma(normalized),
        }
        raw = [self.raw_row(e, t) for e, t in samples]
        if unmatched:
            rospy.logwarn("eval_recorder: %d %s estimates had no truth at their stamp", unmatched, name)
        return entry, raw

    @staticmethod
    def raw_row(est, truth):
        """One estimate for diagnosis: validity, the arbiter's choice, the reject code, the errors and the
        per-axis errors in units of the estimate's own sigma (None where not claimed), its status and its sigmas."""
        row = {"t": est.header.stamp.to_sec(), "valid": bool(est.valid), "selected_source": est.selected_source,
               "reject_reason": est.reject_reason, "true_range": None, "position_error": None,
               "orientation_error": None, "z": None, "status": est.status,
               "sigma": [math.sqrt(v) if 0.0 < v < NOT_ESTIMATED_VARIANCE else None
                         for v in (est.pose.covariance[7 * i] for i in range(6))]}
        if truth is None:
            return row
        pe, pt = est.pose.pose.position, truth.pose.pose.position
        row["true_range"] = math.sqrt(pt.x ** 2 + pt.y ** 2 + pt.z ** 2)
        if est.valid and est.position_valid:
            row["position_error"] = math.dist((pe.x, pe.y, pe.z), (pt.x, pt.y, pt.z))
            row["z"] = list(normalized_errors(est, truth))
        if est.valid and est.orientation_valid:
            row["orientation_error"] = rotation_angle_deg(est.pose.pose.orientation, truth.pose.pose.orientation)
        return row

    def write(self):
        sources, raw = {}, {}
        for name, estimates in self.estimates.items():
            if estimates:
                sources[name], raw[name] = self.evaluate(name, estimates)
        result = {
            "name": self.scenario,
            "range_m": float(self.nominal_range if self.nominal_range is not None else (self.first_truth_range or 0.0)),
            "lighting": self.lighting,
            "sources": sources,
            "raw": raw,
        }
        with open(self.output, "w") as f:
            json.dump(result, f)
        rospy.loginfo("eval_recorder: %s: %s", self.scenario,
                      ", ".join(f"{k} {v['frames']} frames, detection {v['detection_rate']:.2f}" for k, v in sources.items()))


if __name__ == "__main__":
    rospy.init_node("eval_recorder")
    EvalRecorder().run()
