#include "sim_motor_backend.h"

#include <docking_msgs/WheelCommand.h>
#include <docking_msgs/names.h>

namespace omni_base {

SimMotorBackend::SimMotorBackend(ros::NodeHandle& nh, std::size_t wheel_count, double link_timeout_s,
                                 const std::string& frame_id)
    : wheel_count_(wheel_count), link_timeout_s_(link_timeout_s), frame_id_(frame_id) {
  command_pub_ = nh.advertise<docking_msgs::WheelCommand>(docking_msgs::topics::kWheelCommand, 10);
  encoder_sub_ = nh.subscribe(docking_msgs::topics::kWheelEncoders, 10, &SimMotorBackend::onEncoders, this,
                              ros::TransportHints().tcpNoDelay());
}

void SimMotorBackend::onEncoders(const docking_msgs::WheelEncoders::ConstPtr& msg) {
  if (msg->counts.size() != wheel_count_) {
    ++malformed_;
    ROS_ERROR_THROTTLE(5.0, "omni_base: wheels/encoders carries %zu counts, the configuration has %zu wheels",
                       msg->counts.size(), wheel_count_);
    return;
  }
  ++received_;
  pending_ = msg;
}

void SimMotorBackend::send(const std::vector<double>& wheel_rad_s, bool enable, const ros::Time& now) {
  docking_msgs::WheelCommand cmd;
  cmd.header.stamp = now;
  cmd.header.frame_id = frame_id_;
  cmd.enable = enable;
  cmd.velocity = wheel_rad_s;
  command_pub_.publish(cmd);
}

std::vector<EncoderReading> SimMotorBackend::poll(const ros::Time& now) {
  std::vector<EncoderReading> readings;  // the newest message only: the simulator's counts are exact
  if (pending_) {
    const auto msg = pending_;
    pending_.reset();
    if (!link_up_) ROS_INFO("omni_base: simulator encoders arriving");
    link_up_ = true;
    last_received_ = now;
    EncoderReading r;
    r.stamp = msg->header.stamp.isZero() ? now : msg->header.stamp;
    r.counts.assign(msg->counts.begin(), msg->counts.end());
    // Milliseconds of the simulator's clock, wrapping like the board's u32 clock.
    r.source_time_ms = static_cast<uint32_t>(static_cast<uint64_t>(r.stamp.toNSec() / 1000000u) & 0xFFFFFFFFu);
    r.fault = msg->fault;
    if (msg->fault) r.fault_text = "simulator reports a motor fault";
    readings.push_back(r);
  } else if (link_up_ && (now - last_received_).toSec() > link_timeout_s_) {
    link_up_ = false;
    ++link_losses_;
    ROS_ERROR("omni_base: no wheels/encoders for %.2f s: simulator link lost, wheels commanded to zero",
              (now - last_received_).toSec());
  } else if (now < last_received_) {
    last_received_ = now;  // sim time restarted
  }
  return readings;
}

void SimMotorBackend::diagnose(diagnostic_updater::DiagnosticStatusWrapper& stat) const {
  using diagnostic_msgs::DiagnosticStatus;
  if (link_up_) {
    stat.summary(DiagnosticStatus::OK, "simulator encoders arriving");
  } else {
    stat.summary(DiagnosticStatus::ERROR, "no encoder feedback from the simulator");
  }
  stat.add("encoder messages", received_);
  stat.add("malformed messages", malformed_);
  stat.add("link losses", link_losses_);
}

}  // namespace omni_base
