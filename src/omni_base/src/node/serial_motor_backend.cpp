#include "serial_motor_backend.h"

#include <cmath>

namespace omni_base {

SerialMotorBackend::SerialMotorBackend(const SerialBackendConfig& config)
    : config_(config), backoff_(docking_msgs::BackoffParams{config.backoff_min_s, config.backoff_max_s, 2.0}) {
  if (SerialPort::baudConstant(config_.baud) == 0) {
    throw std::runtime_error("serial/baud " + std::to_string(config_.baud) + " is not a supported baud rate");
  }
  if (config_.wheel_count > protocol::kMaxWheels) {
    throw std::runtime_error("the motor protocol carries at most " + std::to_string(protocol::kMaxWheels) + " wheels");
  }
}

void SerialMotorBackend::tryConnect(const ros::Time& now) {
  if (now < next_attempt_) return;
  if (!port_.open(config_.device, config_.baud)) {
    last_error_ = port_.lastError();
    const double wait = backoff_.nextDelay();
    next_attempt_ = now + ros::Duration(wait);
    ROS_ERROR_THROTTLE(5.0, "omni_base: motor board not reachable (%s); retrying in %.1f s", last_error_.c_str(), wait);
    return;
  }
  ++connects_;
  ROS_INFO("omni_base: opened %s at %d baud; waiting for the board to answer", config_.device.c_str(), config_.baud);
  decoder_.reset();
  connected_at_ = now;
  last_frame_at_ = now;  // the board gets link_timeout_s to answer the first command
  enable_.forceResend();
}

void SerialMotorBackend::dropConnection(const ros::Time& now, const std::string& why) {
  if (link_up_) {
    ++link_losses_;
    ROS_ERROR("omni_base: motor link lost: %s. Wheels commanded to zero; reconnecting.", why.c_str());
  } else {
    ROS_ERROR_THROTTLE(5.0, "omni_base: motor board %s: %s", config_.device.c_str(), why.c_str());
  }
  last_error_ = why;
  link_up_ = false;
  port_.close();
  next_attempt_ = now + ros::Duration(backoff_.nextDelay());
}

bool SerialMotorBackend::writeFrame(const protocol::Frame& frame, const ros::Time& now) {
  if (!port_.write(protocol::encodeFrame(frame))) {
    dropConnection(now, port_.lastError());
    return false;
  }
  return true;
}

void SerialMotorBackend::send(const std::vector<double>& wheel_rad_s, bool enable, const ros::Time& now) {
  if (!port_.isOpen()) tryConnect(now);
  if (!port_.isOpen()) return;
  if (enable_.shouldSend(enable)) {
    const uint8_t sequence = sequence_++;
    if (!writeFrame(protocol::makeEnableFrame({sequence, enable}), now)) return;
    enable_.sent(enable, sequence);
  }
  protocol::DutyCommand cmd;
  cmd.sequence = sequence_++;
  for (double w : wheel_rad_s) {
    const double duty = std::isfinite(w) ? config_.drive.dutyFromSpeed(w) : 0.0;
    cmd.duty.push_back(static_cast<int16_t>(std::lround(duty * protocol::kDutyFullScale)));
  }
  writeFrame(protocol::makeDutyFrame(cmd), now);
}

std::vector<EncoderReading> SerialMotorBackend::poll(const ros::Time& now) {
  std::vector<EncoderReading> readings;
  if (!port_.isOpen()) return readings;
  rx_.clear();
  if (!port_.readAvailable(rx_)) {
    dropConnection(now, port_.lastError());
    return readings;
  }
  for (const auto& frame : decoder_.feed(rx_.data(), rx_.size())) {
    const auto state = protocol::parseStateFrame(frame);
    if (!state) continue;
    if (state->encoder_counts.size() != config_.wheel_count) {
      // The board answers, but not as the configured base: a wrong firmware or configuration.
      board_wheel_count_ = state->encoder_counts.size();
      ++wrong_wheel_count_frames_;
      ROS_ERROR_THROTTLE(5.0, "omni_base: board reports %zu wheels, the configuration has %zu",
                         state->encoder_counts.size(), config_.wheel_count);
      continue;
    }
    board_wheel_count_ = state->encoder_counts.size();
    if (!link_up_) {
      ROS_INFO("omni_base: motor board answering on %s", config_.device.c_str());
      backoff_.reset();
    }
    link_up_ = true;
    last_frame_at_ = now;
    EncoderReading reading;
    reading.stamp = now;
    reading.counts = state->encoder_counts;
    reading.source_time_ms = state->board_time_ms;
    enable_.onBoardState(state->sequence, (state->status & protocol::kStatusEnabled) != 0);
    reading.fault = (state->status & protocol::kStatusFault) != 0;
    if (reading.fault) {
      reading.fault_text = std::string((state->faults & protocol::kFaultStall) ? "stall " : "") +
                           ((state->faults & protocol::kFaultOverCurrent) ? "over-current " : "") +
                           ((state->faults & protocol::kFaultUnderVoltage) ? "under-voltage" : "");
    }
    last_status_ = state->status;
    last_faults_ = state->faults;
    readings.push_back(reading);
  }
  if ((now - last_frame_at_).toSec() > config_.link_timeout_s) {
    dropConnection(now, wrongWheelCount() ? "the board answers with " + std::to_string(board_wheel_count_) +
                                          " wheels; the configuration (wheels/names) has " +
                                          std::to_string(config_.wheel_count)
                                    : "no valid frame from the board for " +
                                          std::to_string((now - last_frame_at_).toSec()) + " s");
  }
  return readings;
}

void SerialMotorBackend::diagnose(diagnostic_updater::DiagnosticStatusWrapper& stat) const {
  using diagnostic_msgs::DiagnosticStatus;
  if (!link_up_ && wrongWheelCount()) {
    stat.summaryf(DiagnosticStatus::ERROR, "wrong wheel count: %s", last_error_.c_str());
  } else if (!link_up_) {
    stat.summaryf(DiagnosticStatus::ERROR, "motor board not answering: %s", last_error_.c_str());
  } else if (!enable_.confirmed()) {
    stat.summary(DiagnosticStatus::ERROR, "motor board not in the commanded enable state (rebooted?): re-sending ENABLE");
  } else if (last_status_ & protocol::kStatusFault) {
    stat.summary(DiagnosticStatus::ERROR, "motor board reports a fault");
  } else if (last_status_ & protocol::kStatusWatchdogStopped) {
    stat.summary(DiagnosticStatus::WARN, "motor board watchdog stopped the motors");
  } else {
    stat.summary(DiagnosticStatus::OK, "motor board answering");
  }
  stat.add("device", config_.device);
  stat.add("baud", config_.baud);
  stat.add("frames decoded", decoder_.framesDecoded());
  stat.add("CRC errors", decoder_.crcErrors());
  stat.add("length errors", decoder_.lengthErrors());
  stat.add("garbage bytes", decoder_.garbageBytes());
  stat.add("connections", connects_);
  stat.add("link losses", link_losses_);
  stat.add("board status bits", static_cast<int>(last_status_));
  stat.add("board fault bits", static_cast<int>(last_faults_));
  stat.add("false starts", decoder_.falseStarts());
  stat.add("enable lost (board reboots)", enable_.enableLosses());
  stat.add("board wheel count", board_wheel_count_);
  stat.add("frames with the wrong wheel count", wrong_wheel_count_frames_);
  stat.add("last error", last_error_);
}

}  // namespace omni_base
