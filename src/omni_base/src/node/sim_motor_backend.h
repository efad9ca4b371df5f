#pragma once

#include <docking_msgs/WheelEncoders.h>
#include <ros/ros.h>

#include <mutex>

#include "motor_backend.h"

namespace omni_base {

/// The simulator as a motor board: set-points out on wheels/command (docking_msgs/WheelCommand),
/// encoder counts in on wheels/encoders (docking_msgs/WheelEncoders), all in sim time.
class SimMotorBackend : public MotorBackend {
 public:
  SimMotorBackend(ros::NodeHandle& nh, std::size_t wheel_count, double link_timeout_s, const std::string& frame_id);
  void send(const std::vector<double>& wheel_rad_s, bool enable, const ros::Time& now) override;
  std::vector<EncoderReading> poll(const ros::Time& now) override;
  bool linkUp() const override { return link_up_; }
  std::string describe() const override { return "simulator topics"; }
  void diagnose(diagnostic_updater::DiagnosticStatusWrapper& stat) const override;

 private:
  void onEncoders(const docking_msgs::WheelEncoders::ConstPtr& msg);

  std::size_t wheel_count_;
  double link_timeout_s_;
  std::string frame_id_;
  ros::Publisher command_pub_;
  ros::Subscriber encoder_sub_;
  docking_msgs::WheelEncoders::ConstPtr pending_;
  ros::Time last_received_;
  bool link_up_{false};
  std::uint64_t received_{0};
  std::uint64_t malformed_{0};
  std::uint64_t link_losses_{0};
};

}  // namespace omni_base
