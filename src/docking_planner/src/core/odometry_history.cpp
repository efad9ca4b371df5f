#include "docking_planner/odometry_history.h"

#include <algorithm>
#include <cmath>

namespace docking_planner {

Pose2D advanceAlongTwist(const Pose2D& pose, const BodyTwist& twist, double dt) {
  const double turn = twist.wz * dt;
  // Body-frame displacement of a constant twist: the straight-line formula times the arc factors
  // sin(turn)/turn and (1 - cos(turn))/turn (series near zero, where they are 1 and turn/2).
  double along, across;
  if (std::abs(turn) < 1e-6) {
    along = 1.0 - turn * turn / 6.0;
    across = turn / 2.0;
  } else {
    along = std::sin(turn) / turn;
    across = (1.0 - std::cos(turn)) / turn;
  }
  const double bx = (twist.vx * along - twist.vy * across) * dt;
  const double by = (twist.vx * across + twist.vy * along) * dt;
  const double c = std::cos(pose.yaw), s = std::sin(pose.yaw);
  return Pose2D{pose.x + c * bx - s * by, pose.y + s * bx + c * by, wrapAngle(pose.yaw + turn)};
}

bool OdometryHistory::add(const OdometrySample& sample) {
  if (!std::isfinite(sample.stamp_s) || !std::isfinite(sample.pose.x) || !std::isfinite(sample.pose.y) ||
      !std::isfinite(sample.pose.yaw) || !std::isfinite(sample.twist.vx) || !std::isfinite(sample.twist.vy) ||
      !std::isfinite(sample.twist.wz)) {
    return false;
  }
  if (!samples_.empty() && sample.stamp_s <= samples_.back().stamp_s) return false;
  samples_.push_back(sample);
  while (samples_.size() > 2 && samples_.front().stamp_s < sample.stamp_s - span_s_) samples_.pop_front();
  return true;
}

std::optional<Pose2D> OdometryHistory::poseAt(double stamp_s, double max_extrapolation_s) const {
  if (samples_.empty() || !std::isfinite(stamp_s)) return std::nullopt;
  const OdometrySample& newest = samples_.back();
  if (stamp_s >= newest.stamp_s) {
    const double ahead = stamp_s - newest.stamp_s;
    if (ahead > max_extrapolation_s) return std::nullopt;
    return advanceAlongTwist(newest.pose, newest.twist, ahead);
  }
  if (stamp_s < samples_.front().stamp_s) return std::nullopt;
  // The first sample after the stamp, and the one before it.
  const auto after = std::upper_bound(samples_.begin(), samples_.end(), stamp_s,
                                      [](double t, const OdometrySample& s) { return t < s.stamp_s; });
  const OdometrySample& b = *after;
  const OdometrySample& a = *(after - 1);
  const double f = (stamp_s - a.stamp_s) / (b.stamp_s - a.stamp_s);
  return Pose2D{a.pose.x + f * (b.pose.x - a.pose.x), a.pose.y + f * (b.pose.y - a.pose.y),
                wrapAngle(a.pose.yaw + f * wrapAngle(b.pose.yaw - a.pose.yaw))};
}

}  // namespace docking_planner
