// The base's command path, free of ROS: validation, watchdog, e-stop latch, limits, kinematics.
// The node feeds it commands and a clock and sends what it returns to the motors.
#pragma once

#include <array>
#include <cstdint>
#include <string>
#include <vector>

#include "omni_base/kinematics.h"
#include "omni_base/velocity_limiter.h"

namespace omni_base {

struct BaseControllerConfig {
  AxisLimits limits;
  std::array<double, 3> stop_deceleration{{5.0, 5.0, 15.0}};  ///< used when the base stops on its own, or on a zero command
  double cmd_timeout_s{0.5};
  double max_wheel_speed_rad_s{20.0};
};

/// Why the base is being stopped (kNone: it follows the commands).
enum class StopReason { kNone, kNoCommand, kWatchdog, kEStop, kLinkDown };
const char* toString(StopReason reason);

enum class CommandVerdict { kAccepted, kRejectedNonFinite, kIgnoredEStop };

class BaseController {
 public:
  struct Output {
    std::vector<double> wheel_rad_s;  ///< set-points to send, after all limits
    Twist2D body;                     ///< the body twist those set-points produce
    StopReason stop_reason{StopReason::kNone};
    double wheel_saturation_scale{1.0};  ///< < 1 when wheel speeds had to be scaled down
  };

  BaseController(const OmniKinematics& kinematics, const BaseControllerConfig& config);

  /// A new velocity command at time now_s. Non-finite commands are rejected and do not feed the
  /// watchdog: a stream of NaN must stop the base, not keep it going on an old command.
  CommandVerdict command(const Twist2D& cmd, double now_s);
  /// Latches a stop until release(); commands received while latched are ignored.
  void engageEStop();
  /// Releases the latch. The base moves again only on a command newer than the release.
  void releaseEStop(double now_s);
  bool eStopLatched() const { return estop_latched_; }

  /// One control cycle. link_ok: the motor backend is answering.
  Output update(double now_s, bool link_ok);

  std::uint64_t watchdogTrips() const { return watchdog_trips_; }
  std::uint64_t rejectedCommands() const { return rejected_commands_; }
  double secondsSinceCommand(double now_s) const;
  const BaseControllerConfig& config() const { return config_; }

 private:
  OmniKinematics kinematics_;
  BaseControllerConfig config_;
  VelocityLimiter limiter_;
  Twist2D commanded_;           // last accepted command (already velocity limited)
  Twist2D current_;             // body twist sent last cycle
  double last_command_s_{-1.0};
  double last_update_s_{-1.0};
  bool estop_latched_{false};
  bool watchdog_tripped_{false};
  std::uint64_t watchdog_trips_{0};
  std::uint64_t rejected_commands_{0};
};

}  // namespace omni_base
