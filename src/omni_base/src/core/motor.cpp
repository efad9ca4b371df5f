#include "omni_base/motor.h"

#include <algorithm>
#include <cmath>

namespace omni_base {

double FirstOrderMotor::step(double setpoint_rad_s, double dt_s) {
  if (!std::isfinite(setpoint_rad_s) || !(dt_s > 0.0)) return velocity_rad_s_;
  if (time_constant_s_ <= 0.0) {
    velocity_rad_s_ = setpoint_rad_s;
  } else {
    velocity_rad_s_ += (1.0 - std::exp(-dt_s / time_constant_s_)) * (setpoint_rad_s - velocity_rad_s_);
  }
  return velocity_rad_s_;
}

double MotorDriveModel::dutyFromSpeed(double rad_s) const {
  return std::clamp(rad_s * volts_per_rad_s / supply_volts, -1.0, 1.0);
}

double MotorDriveModel::speedFromDuty(double duty) const {
  return std::clamp(duty, -1.0, 1.0) * supply_volts / volts_per_rad_s;
}

int32_t encoderCountsFromAngle(double angle_rad, double counts_per_rev) {
  const double counts = std::floor(angle_rad / (2.0 * M_PI) * counts_per_rev);
  // A real counter wraps modulo 2^32; do the same through unsigned arithmetic.
  const auto wide = static_cast<int64_t>(std::fmod(counts, 4294967296.0));
  return static_cast<int32_t>(static_cast<uint32_t>(wide));
}

}  // namespace omni_base
