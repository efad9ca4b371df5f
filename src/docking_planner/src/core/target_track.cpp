#include "docking_planner/target_track.h"

#include <cmath>
#include <limits>
#include <stdexcept>

namespace docking_planner {

void validate(const TrackConfig& c) {
  if (!std::isfinite(c.velocity_filter_time_s) || c.velocity_filter_time_s < 0.0) {
    throw std::invalid_argument("velocity_filter_time_s must be a number >= 0");
  }
  if (!std::isfinite(c.min_difference_dt_s) || c.min_difference_dt_s <= 0.0) {
    throw std::invalid_argument("min_difference_dt_s must be positive");
  }
  if (!std::isfinite(c.max_port_speed_mps) || c.max_port_speed_mps < 0.0) {
    throw std::invalid_argument("max_port_speed_mps must be a number >= 0");
  }
  if (!std::isfinite(c.max_port_yaw_rate_radps) || c.max_port_yaw_rate_radps < 0.0) {
    throw std::invalid_argument("max_port_yaw_rate_radps must be a number >= 0");
  }
}

TargetTrack::TargetTrack(const TrackConfig& config) : config_(config) { validate(config_); }

void TargetTrack::reset() {
  pose_ = Pose2D{};
  velocity_ = Vec2::Zero();
  yaw_rate_ = 0.0;
  last_position_stamp_s_.reset();
  last_orientation_stamp_s_.reset();
}

double TargetTrack::lastStamp() const {
  return last_position_stamp_s_ ? *last_position_stamp_s_ : -std::numeric_limits<double>::infinity();
}

double TargetTrack::lastOrientationStamp() const {
  return last_orientation_stamp_s_ ? *last_orientation_stamp_s_ : -std::numeric_limits<double>::infinity();
}

TrackUpdate TargetTrack::update(const TargetObservation& o) {
  TrackUpdate result;
  if (!o.valid) {
    result.reason = o.status.empty() ? "estimate not valid" : "estimate not valid: " + o.status;
    return result;
  }
  if (!std::isfinite(o.stamp_s) || !std::isfinite(o.pose.x) || !std::isfinite(o.pose.y) ||
      (o.orientation_valid && !std::isfinite(o.pose.yaw)) || (o.yaw_rate_valid && !std::isfinite(o.yaw_rate))) {
    result.reason = "estimate contains NaN or infinity";
    return result;
  }
  if (last_position_stamp_s_ && o.stamp_s <= *last_position_stamp_s_) {
    result.reason = "estimate out of order (stamp not after the last one used)";
    return result;
  }

  // Velocities by differencing against the last pose taken, low-pass filtered: raw differences
  // amplify the pose noise by sqrt(2)/dt (paper-notes.md, "Velocities").
  // Two sources disagree by their biases: differencing across a switch would be a velocity spike.
  if (last_position_stamp_s_ && o.source == last_source_) {
    const double dt = o.stamp_s - *last_position_stamp_s_;
    if (dt >= config_.min_difference_dt_s) {
      const double alpha =
          config_.velocity_filter_time_s > 0.0 ? 1.0 - std::exp(-dt / config_.velocity_filter_time_s) : 1.0;
      const Vec2 raw_velocity = (o.pose.position() - pose_.position()) / dt;
      velocity_ = clampNorm(velocity_ + alpha * (raw_velocity - velocity_), config_.max_port_speed_mps);
      std::optional<double> raw_rate;
      if (config_.use_estimate_yaw_rate && o.yaw_rate_valid) {
        raw_rate = o.yaw_rate;
      } else if (o.orientation_valid && last_orientation_stamp_s_) {
        const double dt_yaw = o.stamp_s - *last_orientation_stamp_s_;
        if (dt_yaw >= config_.min_difference_dt_s) raw_rate = wrapAngle(o.pose.yaw - pose_.yaw) / dt_yaw;
      }
      if (raw_rate) {
        yaw_rate_ = clampAbs(yaw_rate_ + alpha * (*raw_rate - yaw_rate_), config_.max_port_yaw_rate_radps);
      }
    }
  } else if (!last_position_stamp_s_ && config_.use_estimate_yaw_rate && o.yaw_rate_valid) {
    yaw_rate_ = clampAbs(o.yaw_rate, config_.max_port_yaw_rate_radps);
  }

  pose_.x = o.pose.x;
  pose_.y = o.pose.y;
  if (o.orientation_valid) {
    pose_.yaw = wrapAngle(o.pose.yaw);
    last_orientation_stamp_s_ = o.stamp_s;
  }  // a position-only estimate keeps the held port axis (predicted from its own stamp)
  last_position_stamp_s_ = o.stamp_s;
  last_source_ = o.source;
  result.accepted = true;
  return result;
}

PortState TargetTrack::predict(double now_s) const {
  PortState s;
  const double dt = last_position_stamp_s_ ? now_s - *last_position_stamp_s_ : 0.0;
  s.velocity = velocity_;
  s.yaw_rate = yaw_rate_;
  // Constant-twist (SE(2) exponential) prediction: a target turning about a point other than the
  // port moves the port on a circle, which a straight-line extrapolation would cut short.
  const double turn = yaw_rate_ * dt;
  Vec2 displacement = velocity_ * dt;
  if (std::abs(yaw_rate_) > 1e-9) {
    displacement =
        (std::sin(turn) / yaw_rate_) * velocity_ + ((1.0 - std::cos(turn)) / yaw_rate_) * perpendicular(velocity_);
    s.velocity = Vec2(std::cos(turn) * velocity_.x() - std::sin(turn) * velocity_.y(),
                      std::sin(turn) * velocity_.x() + std::cos(turn) * velocity_.y());
  }
  s.pose.x = pose_.x + displacement.x();
  s.pose.y = pose_.y + displacement.y();
  const double dt_yaw = last_orientation_stamp_s_ ? now_s - *last_orientation_stamp_s_ : 0.0;
  s.pose.yaw = wrapAngle(pose_.yaw + yaw_rate_ * dt_yaw);
  return s;
}

}  // namespace docking_planner
