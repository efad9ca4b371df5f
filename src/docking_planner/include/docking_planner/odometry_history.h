// The chaser's recent odometry, for placing the cameras in odom at an image's stamp (ROS-free).
//
// Why not tf alone: tf2 does not extrapolate, so an estimate stamped a few milliseconds after the last
// odometry waited for the next odometry message (up to one odometry period, and on a busy machine up
// to the planner's next timer tick). Odometry is smooth over such intervals: interpolating between
// messages, or advancing the newest one by its twist for a bounded interval, places the camera as well
// as tf would, with no wait.
#pragma once

#include <cstddef>
#include <deque>
#include <optional>

#include "docking_planner/planar.h"

namespace docking_planner {

struct OdometrySample {
  double stamp_s{0.0};
  Pose2D pose;      ///< base_link in odom
  BodyTwist twist;  ///< in base_link
};

class OdometryHistory {
 public:
  /// Keeps samples newer than `span_s` before the newest one.
  explicit OdometryHistory(double span_s = 2.0) : span_s_(span_s) {}

  /// Appends a sample. Returns false (and keeps nothing) for a non-finite sample or one not after the
  /// newest; a sample older than the history's span resets nothing.
  bool add(const OdometrySample& sample);

  /// The pose at `stamp_s`: interpolated between the samples around it (position linearly, yaw along
  /// the shorter arc), or the newest sample advanced along its twist (a constant-twist arc) when
  /// `stamp_s` is at most `max_extrapolation_s` after it. Empty when `stamp_s` is older than the
  /// history or farther ahead than that.
  std::optional<Pose2D> poseAt(double stamp_s, double max_extrapolation_s) const;

  bool empty() const { return samples_.empty(); }
  std::size_t size() const { return samples_.size(); }
  double newestStamp() const { return samples_.empty() ? -1e300 : samples_.back().stamp_s; }
  void clear() { samples_.clear(); }

 private:
  double span_s_;
  std::deque<OdometrySample> samples_;
};

/// `pose` moved for `dt` seconds at the body twist `twist` (exact arc for a constant twist).
Pose2D advanceAlongTwist(const Pose2D& pose, const BodyTwist& twist, double dt);

}  // namespace docking_planner
