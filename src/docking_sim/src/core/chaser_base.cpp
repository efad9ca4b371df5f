#include "docking_sim/chaser_base.h"

#include <cmath>

namespace docking_sim {

omni_base::Pose2D integrateTwist(const omni_base::Pose2D& pose, const omni_base::Twist2D& twist, double dt_s) {
  // Exact solution for a constant body twist: the body moves on a circular arc.
  const double dtheta = twist.wz * dt_s;
  double a = 1.0, b = 0.0;  // sin(dθ)/dθ and (1 - cos(dθ))/dθ, with their small-angle limits
  if (std::abs(dtheta) > 1e-9) {
    a = std::sin(dtheta) / dtheta;
    b = (1.0 - std::cos(dtheta)) / dtheta;
  } else {
    b = dtheta / 2.0;
  }
  const double dx_body = (a * twist.vx - b * twist.vy) * dt_s;
  const double dy_body = (b * twist.vx + a * twist.vy) * dt_s;
  const double c = std::cos(pose.yaw), s = std::sin(pose.yaw);
  omni_base::Pose2D out;
  out.x = pose.x + c * dx_body - s * dy_body;
  out.y = pose.y + s * dx_body + c * dy_body;
  out.yaw = std::remainder(pose.yaw + dtheta, 2.0 * M_PI);
  return out;
}

ChaserBase::ChaserBase(const OmniBaseModel& model, double command_timeout_s, const omni_base::Pose2D& start)
    : kinematics_(model.layout),
      time_constant_s_(model.motor_time_constant_s),
      counts_per_rev_(model.encoder_counts_per_rev),
      command_timeout_s_(command_timeout_s),
      motors_(model.layout.drive_angles_rad.size(), omni_base::FirstOrderMotor(model.motor_time_constant_s)),
      setpoint_rad_s_(model.layout.drive_angles_rad.size(), 0.0),
      wheel_angle_rad_(model.layout.drive_angles_rad.size(), 0.0),
      pose_(start) {}

CommandResult ChaserBase::command(bool enable, const std::vector<double>& wheel_rad_s, double now_s) {
  CommandResult result = CommandResult::kAccepted;
  if (wheel_rad_s.size() != motors_.size()) {
    result = CommandResult::kRejectedWrongSize;
  } else {
    for (double w : wheel_rad_s) {
      if (!std::isfinite(w)) result = CommandResult::kRejectedNonFinite;
    }
  }
  if (result != CommandResult::kAccepted) {
    std::fill(setpoint_rad_s_.begin(), setpoint_rad_s_.end(), 0.0);
    return result;
  }
  setpoint_rad_s_ = wheel_rad_s;
  enabled_ = enable;
  last_command_s_ = now_s;
  return result;
}

void ChaserBase::step(double now_s, double dt_s) {
  if (!(dt_s > 0.0)) return;
  const bool live = enabled_ && (now_s - last_command_s_) <= command_timeout_s_;
  std::vector<double> mean_speed(motors_.size(), 0.0);
  for (std::size_t i = 0; i < motors_.size(); ++i) {
    const double setpoint = live ? setpoint_rad_s_[i] : 0.0;
    const double before = motors_[i].velocity();
    const double after = motors_[i].step(setpoint, dt_s);
    // The exact mean of a first-order response over the step: sp + (w0 - w1) * tau / dt.
    mean_speed[i] = setpoint + (before - after) * time_constant_s_ / dt_s;
    if (time_constant_s_ <= 0.0) mean_speed[i] = after;
    wheel_angle_rad_[i] += mean_speed[i] * dt_s;
  }
  pose_ = integrateTwist(pose_, kinematics_.forward(mean_speed), dt_s);
}

omni_base::Twist2D ChaserBase::twist() const { return kinematics_.forward(wheelSpeeds()); }

std::vector<double> ChaserBase::wheelSpeeds() const {
  std::vector<double> out;
  for (const auto& m : motors_) out.push_back(m.velocity());
  return out;
}

std::vector<int32_t> ChaserBase::encoderCounts() const {
  std::vector<int32_t> out;
  for (double angle : wheel_angle_rad_) out.push_back(omni_base::encoderCountsFromAngle(angle, counts_per_rev_));
  return out;
}

}  // namespace docking_sim
