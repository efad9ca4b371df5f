// What the motor bridges make of the firmware's pins, and the wheels behind them (ROS-free).
#pragma once

#include <array>
#include <cstdint>

namespace motor_board_firmware {

constexpr std::size_t kWheels = 3;

/// The drive the bridges apply, read off the MCU's registers as the pins would show it (firmware/
/// board_config.h says which pins). A pin that is not an output reads low (the board's pull-downs).
struct MotorOutputs {
  bool bridges_enabled{false};
  std::array<double, kWheels> duty{};  ///< signed fraction of the supply, -1..1 (0 while a pin is low)
  bool misconfigured{false};           ///< a PWM pin on its timer in a mode the firmware does not use
};

/// Decodes the outputs from the data space (registers at their ATmega328P addresses). A PWM pin on its
/// timer in 8-bit fast PWM, non-inverting, duty (OCR + 1) / 256; off its timer, its PORT bit.
MotorOutputs readMotorOutputs(const uint8_t* data);

struct WheelMotorConfig {
  double volts_per_rad_s{0.55};
  double supply_volts{12.0};
  double time_constant_s{0.02};
  double friction_volts{0.05};  ///< Coulomb friction as the voltage it takes to move: a dead band
};

/// A DC wheel motor: tau dw/dt = V / k - w - sign(w) w_f while the bridge drives it (w_f = friction
/// volts / k; it sticks at rest while |V| / k <= w_f), tau dw/dt = -sign(w) w_f while it coasts (bridge
/// in standby, no braking current). Integrated exactly over each step.
class WheelMotor {
 public:
  explicit WheelMotor(const WheelMotorConfig& config) : config_(config) {}
  void step(double duty, bool driven, double dt_s);
  double speed() const { return speed_rad_s_; }
  double angle() const { return angle_rad_; }
  /// Steady-state speed of a duty (what the lag settles to).
  double steadySpeed(double duty) const;

 private:
  WheelMotorConfig config_;
  double speed_rad_s_{0.0};
  double angle_rad_{0.0};
};

}  // namespace motor_board_firmware
