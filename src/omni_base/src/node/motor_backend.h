// Where the wheel set-points go and the encoder counts come from: the serial motor board, or the
// simulator over topics. The node does not care which.
#pragma once

#include <diagnostic_updater/DiagnosticStatusWrapper.h>
#include <ros/ros.h>

#include <cstdint>
#include <string>
#include <vector>

namespace omni_base {

struct EncoderReading {
  ros::Time stamp;              ///< when the host received (sim: when the simulator latched) the counts
  std::vector<int32_t> counts;
  uint32_t source_time_ms{0};   ///< when the counts were latched, on the source's clock (board: ms since boot)
  bool fault{false};            ///< the backend reports a motor fault
  std::string fault_text;
};

class MotorBackend {
 public:
  virtual ~MotorBackend() = default;
  /// Sends set-points (rad/s per wheel); also where a disconnected backend tries to reconnect.
  virtual void send(const std::vector<double>& wheel_rad_s, bool enable, const ros::Time& now) = 0;
  /// Every encoder reading since the last call, oldest first: each one is judged (a forged or reboot
  /// frame in a burst must reach the encoder tracker, not only the newest).
  virtual std::vector<EncoderReading> poll(const ros::Time& now) = 0;
  /// The board restarted (the encoder tracker saw it): send ENABLE again on the next cycle.
  virtual void forceEnable() {}
  /// The backend is answering.
  virtual bool linkUp() const = 0;
  virtual std::string describe() const = 0;
  virtual void diagnose(diagnostic_updater::DiagnosticStatusWrapper& stat) const = 0;
};

}  // namespace omni_base
