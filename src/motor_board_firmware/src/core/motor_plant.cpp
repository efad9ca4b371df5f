#include "motor_board_firmware/motor_plant.h"

#include <algorithm>
#include <cmath>

#include "board_config.h"
#include "motor_board_firmware/avr_board.h"

namespace motor_board_firmware {
namespace {

#define MBF_LETTER_(x) (#x[0])
#define MBF_LETTER(x) MBF_LETTER_(x)

struct Pin {
  char port;
  int bit;
};

uint16_t portRegister(char port) { return port == 'B' ? reg::kPortB : port == 'C' ? reg::kPortC : reg::kPortD; }
uint16_t ddrRegister(char port) { return port == 'B' ? reg::kDdrB : port == 'C' ? reg::kDdrC : reg::kDdrD; }

bool isOutput(const uint8_t* data, Pin pin) { return (data[ddrRegister(pin.port)] >> pin.bit) & 1u; }
bool outputHigh(const uint8_t* data, Pin pin) {
  return isOutput(data, pin) && ((data[portRegister(pin.port)] >> pin.bit) & 1u);
}

/// The 8-bit timer channel whose output compare pin `pin` is (the ATmega328P's pinout).
struct CompareChannel {
  uint16_t tccr_a, tccr_b, ocr;
  int com_shift;  // COMxA at bits 7:6, COMxB at 5:4
};

bool compareChannelOf(Pin pin, CompareChannel* out) {
  if (pin.port == 'D' && pin.bit == 6) *out = {reg::kTccr0A, reg::kTccr0B, reg::kOcr0A, 6};
  else if (pin.port == 'D' && pin.bit == 5) *out = {reg::kTccr0A, reg::kTccr0B, reg::kOcr0B, 4};
  else if (pin.port == 'B' && pin.bit == 3) *out = {reg::kTccr2A, reg::kTccr2B, reg::kOcr2A, 6};
  else if (pin.port == 'D' && pin.bit == 3) *out = {reg::kTccr2A, reg::kTccr2B, reg::kOcr2B, 4};
  else return false;
  return true;
}

/// Fraction of time the PWM pin is high; sets *misconfigured for a timer mode the model does not know.
double pwmLevel(const uint8_t* data, Pin pin, bool* misconfigured) {
  if (!isOutput(data, pin)) return 0.0;
  CompareChannel channel{};
  if (!compareChannelOf(pin, &channel)) return outputHigh(data, pin) ? 1.0 : 0.0;
  const unsigned com = (data[channel.tccr_a] >> channel.com_shift) & 3u;
  if (com == 0) return outputHigh(data, pin) ? 1.0 : 0.0;
  const unsigned wgm = (data[channel.tccr_a] & 3u) | ((data[channel.tccr_b] >> 1) & 4u);
  const unsigned clock_select = data[channel.tccr_b] & 7u;
  if (com != 2 || wgm != 3 || clock_select == 0) {
    *misconfigured = true;
    return 1.0;  // assume the worst: the motor sees the full supply
  }
  return (data[channel.ocr] + 1.0) / 256.0;
}

}  // namespace

MotorOutputs readMotorOutputs(const uint8_t* data) {
  static const std::array<Pin, kWheels> kPwm = {{{MBF_LETTER(MOTOR0_PWM_PORT), MOTOR0_PWM_BIT},
                                                 {MBF_LETTER(MOTOR1_PWM_PORT), MOTOR1_PWM_BIT},
                                                 {MBF_LETTER(MOTOR2_PWM_PORT), MOTOR2_PWM_BIT}}};
  static const std::array<Pin, kWheels> kDir = {{{MBF_LETTER(MOTOR0_DIR_PORT), MOTOR0_DIR_BIT},
                                                 {MBF_LETTER(MOTOR1_DIR_PORT), MOTOR1_DIR_BIT},
                                                 {MBF_LETTER(MOTOR2_DIR_PORT), MOTOR2_DIR_BIT}}};
  static const Pin kEnable{MBF_LETTER(DRIVER_ENABLE_PORT), DRIVER_ENABLE_BIT};
  MotorOutputs out;
  out.bridges_enabled = outputHigh(data, kEnable);
  for (std::size_t i = 0; i < kWheels; ++i) {
    const double level = pwmLevel(data, kPwm[i], &out.misconfigured);
    out.duty[i] = outputHigh(data, kDir[i]) ? -level : level;
  }
  return out;
}

double WheelMotor::steadySpeed(double duty) const {
  const double volts = duty * config_.supply_volts;
  const double beyond_friction = std::max(0.0, std::abs(volts) - config_.friction_volts);
  return std::copysign(beyond_friction / config_.volts_per_rad_s, volts);
}

void WheelMotor::step(double duty, bool driven, double dt_s) {
  if (!(dt_s > 0.0)) return;
  const double tau = config_.time_constant_s;
  const double friction_rad_s = config_.friction_volts / config_.volts_per_rad_s;
  const double free_rad_s = driven ? duty * config_.supply_volts / config_.volts_per_rad_s : 0.0;
  if (speed_rad_s_ == 0.0 && (!driven || std::abs(free_rad_s) <= friction_rad_s)) return;  // stiction
  // Friction opposes the motion (or, from rest, the drive).
  const double direction = speed_rad_s_ != 0.0 ? std::copysign(1.0, speed_rad_s_) : std::copysign(1.0, free_rad_s);
  double w_next = 0.0, distance = 0.0;
  if (driven) {
    const double target = free_rad_s - direction * friction_rad_s;
    const double decay = std::exp(-dt_s / tau);
    w_next = target + (speed_rad_s_ - target) * decay;
    distance = target * dt_s + (speed_rad_s_ - target) * tau * (1.0 - decay);
  } else {
    const double deceleration = friction_rad_s / tau;
    w_next = speed_rad_s_ - direction * deceleration * dt_s;
    distance = (speed_rad_s_ + w_next) / 2.0 * dt_s;
  }
  if (w_next * direction < 0.0) {
    // Friction stops the wheel within the step; it stays at rest (the drive does not beat friction
    // backwards within one 0.1 ms step at these speeds). Distance up to the stop, on the chord.
    const double t_stop = dt_s * std::abs(speed_rad_s_) / (std::abs(speed_rad_s_) + std::abs(w_next));
    distance = speed_rad_s_ / 2.0 * t_stop;
    w_next = 0.0;
  }
  speed_rad_s_ = w_next;
  angle_rad_ += distance;
}

}  // namespace motor_board_firmware
