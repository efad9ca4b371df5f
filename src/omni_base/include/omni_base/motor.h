// Motor models shared by the driver, the fake motor board and the simulator (ROS-free).
#pragma once

#include <cstdint>

namespace omni_base {

/// A DC wheel motor's speed as a first-order lag behind its set-point: tau dw/dt = setpoint - w.
/// Used by the fake motor board and the simulator, so both respond like the same motor.
class FirstOrderMotor {
 public:
  /// time_constant_s <= 0 makes the motor follow its set-point instantly.
  explicit FirstOrderMotor(double time_constant_s = 0.0) : time_constant_s_(time_constant_s) {}

  /// Advances dt_s seconds towards setpoint_rad_s (exact discretisation) and returns the new speed.
  double step(double setpoint_rad_s, double dt_s);
  double velocity() const { return velocity_rad_s_; }
  void reset(double velocity_rad_s = 0.0) { velocity_rad_s_ = velocity_rad_s; }

 private:
  double time_constant_s_;
  double velocity_rad_s_{0.0};
};

/// The motor board's drive: wheel speed is linear in motor voltage (the paper's finding), and the
/// board applies a PWM duty of the supply voltage.
struct MotorDriveModel {
  double volts_per_rad_s{0.5};  ///< motor voltage per rad/s of wheel speed (from calibration)
  double supply_volts{12.0};    ///< battery voltage the PWM chops

  /// Duty in [-1, 1] for a wheel speed, clamped at full supply.
  double dutyFromSpeed(double rad_s) const;
  /// Steady-state wheel speed that a duty produces.
  double speedFromDuty(double duty) const;
  /// Highest wheel speed the supply allows, rad/s.
  double maxSpeed() const { return supply_volts / volts_per_rad_s; }
};

/// An incremental encoder: the wrapping 32-bit count a board reports for an accumulated wheel angle.
int32_t encoderCountsFromAngle(double angle_rad, double counts_per_rev);

}  // namespace omni_base
