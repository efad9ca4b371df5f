// Velocity and acceleration limits for a planar body twist (ROS-free).
#pragma once

#include <array>

#include "omni_base/kinematics.h"

namespace omni_base {

/// Per-axis limits, in the order (vx [m/s], vy [m/s], wz [rad/s]) and their derivatives per second.
struct AxisLimits {
  std::array<double, 3> max_velocity{{0.4, 0.4, 1.5}};
  std::array<double, 3> max_acceleration{{0.8, 0.8, 3.0}};
};

/// Limits a twist so that no axis exceeds its limit, scaling all three axes by one factor: the
/// direction of motion (and the curvature of the path) is kept, only the speed changes. A per-axis
/// clamp would turn a diagonal command into a different direction, which is how a robot ends up
/// somewhere nobody asked it to go.
class VelocityLimiter {
 public:
  explicit VelocityLimiter(const AxisLimits& limits);

  /// Scales `desired` into the velocity limits.
  Twist2D limitVelocity(const Twist2D& desired) const;
  /// Moves from `current` towards `desired` by at most acceleration * dt per axis, scaling the whole
  /// change by one factor. `acceleration` overrides the configured limits (e.g. a harder stop).
  static Twist2D limitAcceleration(const Twist2D& current, const Twist2D& desired, double dt_s,
                                   const std::array<double, 3>& acceleration);
  /// Velocity limit, then acceleration limit with the configured accelerations.
  Twist2D limit(const Twist2D& current, const Twist2D& desired, double dt_s) const;

  const AxisLimits& limits() const { return limits_; }

 private:
  AxisLimits limits_;
};

/// Scales all wheel speeds by one factor so that none exceeds max_rad_s; returns the factor (<= 1).
/// Scaling all wheels together keeps the direction of the body motion.
double saturateWheelSpeeds(std::vector<double>& wheel_rad_s, double max_rad_s);

}  // namespace omni_base
