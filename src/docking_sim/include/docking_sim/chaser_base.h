// The chaser's omni base as the simulator moves it: wheel set-points in, first-order motors,
// forward kinematics, exact planar integration, encoder counts out (ROS-free).
#pragma once

#include <cstdint>
#include <vector>

#include "docking_sim/configs.h"
#include "omni_base/kinematics.h"
#include "omni_base/motor.h"

namespace docking_sim {

enum class CommandResult {
  kAccepted,
  kRejectedNonFinite,
  kRejectedWrongSize,
  kIgnoredScripted,  ///< the scenario scripts the chaser's motion (Simulation::wheelCommand)
};

class ChaserBase {
 public:
  ChaserBase(const OmniBaseModel& model, double command_timeout_s, const omni_base::Pose2D& start);

  /// A wheel command received at sim time now_s. Non-finite or wrongly sized commands are rejected:
  /// the set-points become zero and the values are never integrated.
  CommandResult command(bool enable, const std::vector<double>& wheel_rad_s, double now_s);

  /// Advances dt_s seconds ending at sim time now_s + dt_s. Disabled or stale commands (older than
  /// the timeout) drive the set-points to zero, as the motor board's own watchdog does.
  void step(double now_s, double dt_s);

  const omni_base::Pose2D& pose() const { return pose_; }
  /// Puts the base at `pose` (tools rendering a given path: sim_render --approach); wheels untouched.
  void place(const omni_base::Pose2D& pose) { pose_ = pose; }
  /// Body twist from the current wheel speeds (base_link).
  omni_base::Twist2D twist() const;
  std::vector<int32_t> encoderCounts() const;
  const std::vector<double>& wheelAngles() const { return wheel_angle_rad_; }
  std::vector<double> wheelSpeeds() const;
  bool motorsEnabled() const { return enabled_; }
  std::size_t wheelCount() const { return motors_.size(); }

 private:
  omni_base::OmniKinematics kinematics_;
  double time_constant_s_;
  double counts_per_rev_;
  double command_timeout_s_;
  std::vector<omni_base::FirstOrderMotor> motors_;
  std::vector<double> setpoint_rad_s_;
  std::vector<double> wheel_angle_rad_;
  bool enabled_{false};
  double last_command_s_{-1e9};
  omni_base::Pose2D pose_;
};

/// Moves a planar pose by a constant body twist for dt seconds (exact arc, not Euler).
omni_base::Pose2D integrateTwist(const omni_base::Pose2D& pose, const omni_base::Twist2D& twist, double dt_s);

}  // namespace docking_sim
