#include "omni_base/base_controller.h"

#include <cmath>
#include <stdexcept>

namespace omni_base {

const char* toString(StopReason reason) {
  switch (reason) {
    case StopReason::kNone: return "none";
    case StopReason::kNoCommand: return "no command yet";
    case StopReason::kWatchdog: return "cmd_vel timeout";
    case StopReason::kEStop: return "e-stop latched";
    case StopReason::kLinkDown: return "motor link down";
  }
  return "unknown";
}

BaseController::BaseController(const OmniKinematics& kinematics, const BaseControllerConfig& config)
    : kinematics_(kinematics), config_(config), limiter_(config.limits) {
  if (!(config_.cmd_timeout_s > 0.0)) throw std::invalid_argument("cmd_vel timeout must be positive");
  if (!(config_.max_wheel_speed_rad_s > 0.0)) throw std::invalid_argument("max wheel speed must be positive");
  for (double d : config_.stop_deceleration) {
    if (!(d > 0.0) || !std::isfinite(d)) throw std::invalid_argument("stop deceleration must be positive and finite");
  }
}

CommandVerdict BaseController::command(const Twist2D& cmd, double now_s) {
  if (!std::isfinite(cmd.vx) || !std::isfinite(cmd.vy) || !std::isfinite(cmd.wz)) {
    ++rejected_commands_;
    return CommandVerdict::kRejectedNonFinite;
  }
  if (estop_latched_) return CommandVerdict::kIgnoredEStop;
  commanded_ = limiter_.limitVelocity(cmd);
  last_command_s_ = now_s;
  watchdog_tripped_ = false;
  return CommandVerdict::kAccepted;
}

void BaseController::engageEStop() {
  estop_latched_ = true;
  commanded_ = Twist2D{};
}

void BaseController::releaseEStop(double /*now_s*/) {
  estop_latched_ = false;
  // Forget the command from before the latch: only a new command moves the base again.
  commanded_ = Twist2D{};
  last_command_s_ = -1.0;
}

double BaseController::secondsSinceCommand(double now_s) const {
  return last_command_s_ < 0.0 ? INFINITY : now_s - last_command_s_;
}

BaseController::Output BaseController::update(double now_s, bool link_ok) {
  double dt = last_update_s_ < 0.0 ? 0.0 : now_s - last_update_s_;
  if (dt < 0.0) {
    // Time went backwards (a bag restarted with --clock): start over from rest.
    dt = 0.0;
    current_ = Twist2D{};
    last_command_s_ = -1.0;
  }
  last_update_s_ = now_s;

  Output out;
  if (estop_latched_) {
    out.stop_reason = StopReason::kEStop;
  } else if (!link_ok) {
    out.stop_reason = StopReason::kLinkDown;
  } else if (last_command_s_ < 0.0) {
    out.stop_reason = StopReason::kNoCommand;
  } else if (now_s - last_command_s_ > config_.cmd_timeout_s) {
    out.stop_reason = StopReason::kWatchdog;
    if (!watchdog_tripped_) {
      watchdog_tripped_ = true;
      ++watchdog_trips_;
    }
  }

  const bool zero_command = commanded_.vx == 0.0 && commanded_.vy == 0.0 && commanded_.wz == 0.0;
  if (out.stop_reason == StopReason::kNone && !zero_command) {
    current_ = VelocityLimiter::limitAcceleration(current_, commanded_, dt, config_.limits.max_acceleration);
  } else if (out.stop_reason == StopReason::kNone) {
    // A command of exactly zero is a stop (the planner's HOLD, DOCKED, a cancel): as hard as the base's
    // own stops. At max_acceleration a HOLD took 0.38 s to bring 0.3 m/s to rest, over the 0.6 s budget
    // from a perception loss to still wheels.
    current_ = VelocityLimiter::limitAcceleration(current_, Twist2D{}, dt, config_.stop_deceleration);
  } else if (out.stop_reason == StopReason::kLinkDown) {
    // Nothing reaches the motors anyway; the board's own watchdog stops them. Restart from rest.
    current_ = Twist2D{};
  } else {
    current_ = VelocityLimiter::limitAcceleration(current_, Twist2D{}, dt, config_.stop_deceleration);
  }

  out.wheel_rad_s = kinematics_.inverse(current_);
  out.wheel_saturation_scale = saturateWheelSpeeds(out.wheel_rad_s, config_.max_wheel_speed_rad_s);
  if (out.wheel_saturation_scale < 1.0) {
    // Keep the state consistent with what the wheels can do, so the next ramp starts from reality.
    current_ = Twist2D{current_.vx * out.wheel_saturation_scale, current_.vy * out.wheel_saturation_scale,
                       current_.wz * out.wheel_saturation_scale};
  }
  out.body = current_;
  return out;
}

}  // namespace omni_base
