// A software stand-in for the motor board (ROS-free): speaks the motor protocol, drives each wheel
// through a first-order motor lag, counts encoder ticks, and can misbehave on request (stall, drop
// replies, send garbage) so that the driver's error handling can be tested without hardware.
#pragma once

#include <cstdint>
#include <random>
#include <vector>

#include "omni_base/motor.h"
#include "omni_base/motor_protocol.h"

namespace omni_base {

struct FakeMotorBoardConfig {
  std::size_t wheel_count{3};
  MotorDriveModel drive;
  double motor_time_constant_s{0.02};
  double counts_per_rev{1320.0};
  double watchdog_s{MP_BOARD_WATCHDOG_MS / 1000.0};  ///< no valid command for this long: the board stops the motors
  uint32_t random_seed{42};
};

class FakeMotorBoard {
 public:
  explicit FakeMotorBoard(const FakeMotorBoardConfig& config);

  /// Bytes from the host at board time now_s; returns the bytes the board sends back.
  std::vector<uint8_t> receive(const uint8_t* data, std::size_t size, double now_s);
  /// Advances the motors to board time now_s (call often; the lag is integrated exactly per step).
  void advanceTo(double now_s);

  // Misbehaviour.
  void setStalled(bool stalled) { stalled_ = stalled; }
  void setReplyDropProbability(double p) { drop_probability_ = p; }
  void setGarbageBetweenFrames(bool on) { garbage_ = on; }
  void resetCounters();  ///< like a board reboot: counters, set-points and the board clock back to zero, disabled
  /// A STATE frame in the board's format carrying the given board time and counts, as a glitching
  /// firmware, a second writer on the port or a replayed log would send it; the board itself is unchanged.
  std::vector<uint8_t> forgedState(uint32_t board_time_ms, const std::vector<int32_t>& counts) const;
  /// The board's own STATE frame as of now, repeating the last answered sequence.
  std::vector<uint8_t> currentState() { return stateReply(last_reply_sequence_); }

  const std::vector<double>& wheelSpeeds() const { return speed_rad_s_; }
  const std::vector<double>& wheelAngles() const { return angle_rad_; }  ///< true angles (a reboot keeps them)
  bool enabled() const { return enabled_; }
  uint32_t boardTimeMs() const;  ///< ms since the last (re)boot, wrapping like the real board's u32
  bool watchdogStopped() const { return watchdog_stopped_; }
  std::uint64_t framesReceived() const { return frames_received_; }
  const protocol::StreamDecoder& decoder() const { return decoder_; }

 private:
  std::vector<uint8_t> stateReply(uint8_t sequence);

  FakeMotorBoardConfig config_;
  protocol::StreamDecoder decoder_;
  std::vector<FirstOrderMotor> motors_;
  std::vector<double> setpoint_rad_s_;
  std::vector<double> speed_rad_s_;
  std::vector<double> angle_rad_;
  std::vector<double> boot_angle_rad_;  ///< the true angles at the last (re)boot: the counters count from them
  uint8_t last_reply_sequence_{0};
  bool enabled_{false};
  bool watchdog_stopped_{false};
  bool stalled_{false};
  bool garbage_{false};
  double drop_probability_{0.0};
  double now_s_{0.0};
  double boot_s_{0.0};            ///< host time of the last (re)boot: the board clock counts from it
  double last_advance_s_{-1.0};
  double last_command_s_{-1.0};
  std::uint64_t frames_received_{0};
  std::mt19937 rng_;
};

}  // namespace omni_base
