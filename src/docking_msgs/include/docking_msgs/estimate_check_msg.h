// EstimateFields from a TargetEstimate message and OdometryFields from a nav_msgs/Odometry, for the
// ROS-free checks of estimate_check.h.
#pragma once

#include <algorithm>
#include <array>
#include <string>

#include "docking_msgs/TargetEstimate.h"
#include "docking_msgs/estimate_check.h"

namespace docking_msgs {
namespace checks {

/// Position, orientation (x, y, z, w) and twist (linear, angular) of any message with pose.pose and
/// twist.twist (TargetEstimate, nav_msgs/Odometry; a template: docking_msgs needs no nav_msgs).
template <typename Msg>
void copyPoseAndTwist(const Msg& msg, std::array<double, 3>* position, std::array<double, 4>* orientation_xyzw,
                      std::array<double, 6>* twist) {
  const auto& p = msg.pose.pose.position;
  const auto& q = msg.pose.pose.orientation;
  const auto& v = msg.twist.twist.linear;
  const auto& w = msg.twist.twist.angular;
  *position = {p.x, p.y, p.z};
  *orientation_xyzw = {q.x, q.y, q.z, q.w};
  *twist = {v.x, v.y, v.z, w.x, w.y, w.z};
}

/// The numbers of a nav_msgs/Odometry checked (its stamp apart, with checkStamp).
template <typename OdometryMsg>
OdometryProblem checkOdometry(const OdometryMsg& msg) {
  OdometryFields f;
  copyPoseAndTwist(msg, &f.position, &f.orientation_xyzw, &f.twist);
  return checkOdometryFields(f);
}

inline EstimateFields fieldsOf(const TargetEstimate& msg) {
  EstimateFields f;
  f.has_frame_id = !msg.header.frame_id.empty();
  f.valid = msg.valid;
  f.position_valid = msg.position_valid;
  f.orientation_valid = msg.orientation_valid;
  f.twist_valid = msg.twist_valid;
  copyPoseAndTwist(msg, &f.position, &f.orientation_xyzw, &f.twist);
  std::copy(msg.pose.covariance.begin(), msg.pose.covariance.end(), f.pose_covariance.begin());
  std::copy(msg.twist.covariance.begin(), msg.twist.covariance.end(), f.twist_covariance.begin());
  f.range_m = msg.range_m;
  return f;
}

inline EstimateProblem checkEstimate(const TargetEstimate& msg) { return checkEstimateFields(fieldsOf(msg)); }

/// For an estimator about to publish: a valid estimate that would fail checkEstimate() goes out as not
/// valid, with the problem in `status` and REJECT_IMPLAUSIBLE_POSE, rather than be refused downstream.
/// Returns the problem (kNone: unchanged).
inline EstimateProblem withdrawIfMalformed(TargetEstimate* msg) {
  const EstimateProblem problem = checkEstimate(*msg);
  if (problem == EstimateProblem::kNone) return problem;
  msg->valid = msg->position_valid = msg->orientation_valid = msg->twist_valid = false;
  msg->status = std::string("own output withdrawn: ") + estimateProblemName(problem);
  msg->reject_reason = TargetEstimate::REJECT_IMPLAUSIBLE_POSE;
  return problem;
}

}  // namespace checks
}  // namespace docking_msgs
