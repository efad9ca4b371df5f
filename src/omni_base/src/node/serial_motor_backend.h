#pragma once

#include <cstdint>
#include <string>

#include "motor_backend.h"
#include "omni_base/board_session.h"
#include "omni_base/motor.h"
#include "omni_base/motor_protocol.h"
#include <docking_msgs/reconnect_backoff.h>
#include "omni_base/serial_port.h"

namespace omni_base {

struct SerialBackendConfig {
  std::string device;
  int baud{115200};
  double link_timeout_s{0.25};
  double backoff_min_s{0.1};
  double backoff_max_s{2.0};
  std::size_t wheel_count{3};
  MotorDriveModel drive;
};

/// Talks to the motor board over a serial port (protocol in README.md). Any failure (the port
/// cannot be opened, a read/write error, no valid frame for link_timeout_s) closes the port, marks
/// the link down and retries with exponential back-off.
class SerialMotorBackend : public MotorBackend {
 public:
  explicit SerialMotorBackend(const SerialBackendConfig& config);
  void send(const std::vector<double>& wheel_rad_s, bool enable, const ros::Time& now) override;
  std::vector<EncoderReading> poll(const ros::Time& now) override;
  void forceEnable() override { enable_.forceResend(); }
  bool linkUp() const override { return link_up_; }
  std::string describe() const override { return "serial " + config_.device; }
  void diagnose(diagnostic_updater::DiagnosticStatusWrapper& stat) const override;

 private:
  void tryConnect(const ros::Time& now);
  void dropConnection(const ros::Time& now, const std::string& why);
  bool writeFrame(const protocol::Frame& frame, const ros::Time& now);
  /// The board's last STATE frame carried another wheel count than the configuration's.
  bool wrongWheelCount() const { return board_wheel_count_ != 0 && board_wheel_count_ != config_.wheel_count; }

  SerialBackendConfig config_;
  SerialPort port_;
  protocol::StreamDecoder decoder_;
  docking_msgs::ReconnectBackoff backoff_;
  std::vector<uint8_t> rx_;
  bool link_up_{false};
  EnableHandshake enable_;
  uint8_t sequence_{0};
  ros::Time connected_at_;
  ros::Time last_frame_at_;
  ros::Time next_attempt_;
  uint8_t last_status_{0};
  uint8_t last_faults_{0};
  std::uint64_t link_losses_{0};
  std::uint64_t connects_{0};
  std::size_t board_wheel_count_{0};          ///< wheels in the board's last STATE frame (0: none yet)
  std::uint64_t wrong_wheel_count_frames_{0};
  std::string last_error_;
};

}  // namespace omni_base
