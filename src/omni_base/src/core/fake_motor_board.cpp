#include "omni_base/fake_motor_board.h"

#include <algorithm>
#include <cmath>
#include <stdexcept>

namespace omni_base {

FakeMotorBoard::FakeMotorBoard(const FakeMotorBoardConfig& config)
    : config_(config),
      motors_(config.wheel_count, FirstOrderMotor(config.motor_time_constant_s)),
      setpoint_rad_s_(config.wheel_count, 0.0),
      speed_rad_s_(config.wheel_count, 0.0),
      angle_rad_(config.wheel_count, 0.0),
      boot_angle_rad_(config.wheel_count, 0.0),
      rng_(config.random_seed) {
  if (config_.wheel_count == 0 || config_.wheel_count > protocol::kMaxWheels) {
    throw std::invalid_argument("fake motor board: wheel count must be 1.." + std::to_string(protocol::kMaxWheels));
  }
}

void FakeMotorBoard::resetCounters() {
  boot_angle_rad_ = angle_rad_;  // the wheels keep their true angle; the counters restart at zero
  for (auto& s : setpoint_rad_s_) s = 0.0;
  for (auto& m : motors_) m.reset();
  for (auto& s : speed_rad_s_) s = 0.0;
  enabled_ = false;
  watchdog_stopped_ = false;
  last_command_s_ = -1.0;
  boot_s_ = now_s_;
  decoder_.reset();
}

uint32_t FakeMotorBoard::boardTimeMs() const {
  const auto ms = static_cast<uint64_t>(std::llround(std::max(0.0, now_s_ - boot_s_) * 1000.0));
  return static_cast<uint32_t>(ms & 0xFFFFFFFFu);
}

std::vector<uint8_t> FakeMotorBoard::receive(const uint8_t* data, std::size_t size, double now_s) {
  now_s_ = now_s;
  std::vector<uint8_t> out;
  for (const auto& frame : decoder_.feed(data, size)) {
    ++frames_received_;
    uint8_t sequence = 0;
    if (auto duty = protocol::parseDutyFrame(frame)) {
      if (duty->duty.size() != config_.wheel_count) continue;  // wrong wheel count: ignore, no reply
      for (std::size_t i = 0; i < duty->duty.size(); ++i) {
        setpoint_rad_s_[i] = config_.drive.speedFromDuty(static_cast<double>(duty->duty[i]) / protocol::kDutyFullScale);
      }
      sequence = duty->sequence;
    } else if (auto enable = protocol::parseEnableFrame(frame)) {
      enabled_ = enable->enable;
      sequence = enable->sequence;
    } else {
      continue;  // unknown frame type: a real board ignores it
    }
    last_command_s_ = now_s;
    watchdog_stopped_ = false;
    if (std::uniform_real_distribution<double>(0.0, 1.0)(rng_) < drop_probability_) continue;
    if (garbage_) {
      // A few random bytes, sometimes including a false start sequence.
      std::uniform_int_distribution<int> byte(0, 255);
      for (int i = 0; i < 7; ++i) out.push_back(static_cast<uint8_t>(byte(rng_)));
      out.push_back(protocol::kStart1);
      out.push_back(protocol::kStart2);
      out.push_back(0x81);
    }
    const auto reply = stateReply(sequence);
    out.insert(out.end(), reply.begin(), reply.end());
  }
  return out;
}

void FakeMotorBoard::advanceTo(double now_s) {
  const double dt_s = last_advance_s_ < 0.0 ? 0.0 : std::max(0.0, now_s - last_advance_s_);
  last_advance_s_ = now_s;
  now_s_ = now_s;
  if (last_command_s_ >= 0.0 && now_s_ - last_command_s_ > config_.watchdog_s) watchdog_stopped_ = true;
  const bool driving = enabled_ && !watchdog_stopped_;
  for (std::size_t i = 0; i < motors_.size(); ++i) {
    const double target = driving ? setpoint_rad_s_[i] : 0.0;
    if (stalled_) {
      motors_[i].reset(0.0);
    } else {
      motors_[i].step(target, dt_s);
    }
    speed_rad_s_[i] = motors_[i].velocity();
    angle_rad_[i] += speed_rad_s_[i] * dt_s;
  }
}

std::vector<uint8_t> FakeMotorBoard::stateReply(uint8_t sequence) {
  protocol::BoardState state;
  state.sequence = sequence;
  state.status = static_cast<uint8_t>((enabled_ ? protocol::kStatusEnabled : 0) |
                                      (watchdog_stopped_ ? protocol::kStatusWatchdogStopped : 0) |
                                      (stalled_ ? protocol::kStatusFault : 0));
  state.faults = stalled_ ? protocol::kFaultStall : 0;
  for (std::size_t i = 0; i < angle_rad_.size(); ++i) {
    state.encoder_counts.push_back(encoderCountsFromAngle(angle_rad_[i] - boot_angle_rad_[i], config_.counts_per_rev));
  }
  state.board_time_ms = boardTimeMs();
  last_reply_sequence_ = sequence;
  return protocol::encodeFrame(protocol::makeStateFrame(state));
}

std::vector<uint8_t> FakeMotorBoard::forgedState(uint32_t board_time_ms, const std::vector<int32_t>& counts) const {
  protocol::BoardState state;
  state.sequence = last_reply_sequence_;
  state.status = enabled_ ? protocol::kStatusEnabled : 0;
  state.encoder_counts = counts;
  state.board_time_ms = board_time_ms;
  return protocol::encodeFrame(protocol::makeStateFrame(state));
}

}  // namespace omni_base
