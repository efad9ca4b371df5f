#include "omni_base/velocity_limiter.h"

#include <algorithm>
#include <cmath>
#include <stdexcept>

namespace omni_base {
namespace {

std::array<double, 3> asArray(const Twist2D& t) { return {t.vx, t.vy, t.wz}; }

// Largest factor in (0, 1] such that |factor * value_i| <= limit_i on every axis.
double uniformScale(const std::array<double, 3>& values, const std::array<double, 3>& limit) {
  double scale = 1.0;
  for (std::size_t i = 0; i < 3; ++i) {
    const double magnitude = std::abs(values[i]);
    if (magnitude > limit[i]) scale = std::min(scale, limit[i] / magnitude);
  }
  return scale;
}

}  // namespace

VelocityLimiter::VelocityLimiter(const AxisLimits& limits) : limits_(limits) {
  for (std::size_t i = 0; i < 3; ++i) {
    if (!(limits_.max_velocity[i] > 0.0) || !std::isfinite(limits_.max_velocity[i]) ||
        !(limits_.max_acceleration[i] > 0.0) || !std::isfinite(limits_.max_acceleration[i])) {
      throw std::invalid_argument("velocity and acceleration limits must be positive and finite");
    }
  }
}

Twist2D VelocityLimiter::limitVelocity(const Twist2D& desired) const {
  const double s = uniformScale(asArray(desired), limits_.max_velocity);
  return Twist2D{desired.vx * s, desired.vy * s, desired.wz * s};
}

Twist2D VelocityLimiter::limitAcceleration(const Twist2D& current, const Twist2D& desired, double dt_s,
                                           const std::array<double, 3>& acceleration) {
  if (!(dt_s > 0.0)) return current;
  const std::array<double, 3> change{desired.vx - current.vx, desired.vy - current.vy, desired.wz - current.wz};
  const std::array<double, 3> max_change{acceleration[0] * dt_s, acceleration[1] * dt_s, acceleration[2] * dt_s};
  const double s = uniformScale(change, max_change);
  return Twist2D{current.vx + change[0] * s, current.vy + change[1] * s, current.wz + change[2] * s};
}

Twist2D VelocityLimiter::limit(const Twist2D& current, const Twist2D& desired, double dt_s) const {
  return limitAcceleration(current, limitVelocity(desired), dt_s, limits_.max_acceleration);
}

double saturateWheelSpeeds(std::vector<double>& wheel_rad_s, double max_rad_s) {
  double largest = 0.0;
  for (double w : wheel_rad_s) largest = std::max(largest, std::abs(w));
  if (largest <= max_rad_s || largest == 0.0) return 1.0;
  const double scale = max_rad_s / largest;
  for (double& w : wheel_rad_s) w *= scale;
  return scale;
}

}  // namespace omni_base
