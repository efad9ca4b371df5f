// omni_base: cmd_vel in, wheel set-points out to the motor board (serial) or the simulator, odometry
// back. The command path and the odometry are omni_base_core; this file wires them to ROS.
#include <diagnostic_updater/diagnostic_updater.h>
#include <docking_settings/ros_loader.h>
#include <docking_settings/run_node.h>
#include <docking_msgs/WheelState.h>
#include <docking_msgs/names.h>
#include <geometry_msgs/TransformStamped.h>
#include <geometry_msgs/Twist.h>
#include <nav_msgs/Odometry.h>
#include <ros/ros.h>
#include <sensor_msgs/JointState.h>
#include <std_msgs/Bool.h>
#include <std_srvs/Trigger.h>
#include <tf2/LinearMath/Quaternion.h>
#include <tf2_ros/transform_broadcaster.h>

#include <cmath>
#include <memory>

#include "omni_base/base_controller.h"
#include "omni_base/board_session.h"
#include "omni_base/encoder_tracker.h"
#include "omni_base/odometry.h"
#include "omni_base/base_settings.h"
#include "serial_motor_backend.h"
#include "sim_motor_backend.h"

namespace omni_base {
namespace {

struct NodeConfig {
  std::string backend;
  double control_rate_hz{50.0};
  std::vector<std::string> wheel_names;
  WheelLayout layout;
  EncoderTrackerConfig encoders;
  MotorDriveModel drive;
  BaseControllerConfig controller;
  SerialBackendConfig serial;
  std::string odom_frame;
  std::string base_frame;
  bool publish_tf{true};
  std::vector<double> pose_covariance;
  std::vector<double> twist_covariance;
};

NodeConfig loadConfig(const ros::NodeHandle& pnh) {
  OmniBaseSettings s;
  docking_settings::loadSettings(pnh, s);
  docking_settings::warnUnknownKeys(pnh, s);
  const docking_settings::ParamReader reader(pnh);
  reader.validated([&] { validate(s); });
  if (SerialPort::baudConstant(s.serial.baud) == 0) reader.invalid("serial/baud", "not a baud rate the serial port supports");
  NodeConfig c;
  c.backend = s.backend;
  c.control_rate_hz = s.control_rate_hz;
  c.wheel_names = s.wheels.names;
  c.layout = wheelLayout(s.wheels);
  c.drive = driveModel(s.motor);

  c.encoders.wheel_count = c.wheel_names.size();
  c.encoders.counts_per_rev = s.wheels.encoder_counts_per_rev;
  c.encoders.counter_bits = s.wheels.encoder_bits;
  c.encoders.max_plausible_rad_s = s.encoders.max_plausible_speed_factor * c.drive.maxSpeed();

  auto toArray = [](const std::vector<double>& v) { return std::array<double, 3>{v[0], v[1], v[2]}; };
  c.controller.limits.max_velocity = toArray(s.limits.max_velocity);
  c.controller.limits.max_acceleration = toArray(s.limits.max_acceleration);
  c.controller.stop_deceleration = toArray(s.limits.stop_deceleration);
  c.controller.cmd_timeout_s = s.watchdog.cmd_vel_timeout_s;
  c.controller.max_wheel_speed_rad_s = c.drive.maxSpeed();

  c.serial.device = s.serial.device;
  c.serial.baud = s.serial.baud;
  c.serial.link_timeout_s = s.serial.link_timeout_s;
  c.serial.backoff_min_s = s.serial.reconnect_backoff_min_s;
  c.serial.backoff_max_s = s.serial.reconnect_backoff_max_s;
  c.serial.wheel_count = c.wheel_names.size();
  c.serial.drive = c.drive;

  c.odom_frame = s.odometry.frame_id;
  c.base_frame = s.odometry.child_frame_id;
  c.publish_tf = s.odometry.publish_tf;
  c.pose_covariance = s.odometry.pose_covariance_diagonal;
  c.twist_covariance = s.odometry.twist_covariance_diagonal;
  return c;
}

}  // namespace

class OmniBaseNode {
 public:
  OmniBaseNode(ros::NodeHandle& nh, ros::NodeHandle& pnh)
      : config_(loadConfig(pnh)),
        kinematics_(config_.layout),
        controller_(kinematics_, config_.controller),
        encoders_(config_.encoders),
        last_setpoints_(config_.wheel_names.size(), 0.0) {
    if (config_.backend == "serial") {
      backend_ = std::make_unique<SerialMotorBackend>(config_.serial);
    } else {
      backend_ = std::make_unique<SimMotorBackend>(nh, config_.wheel_names.size(), config_.serial.link_timeout_s,
                                                   config_.base_frame);
    }
    odom_pub_ = nh.advertise<nav_msgs::Odometry>(docking_msgs::topics::kOdom, 20);
    wheel_state_pub_ = nh.advertise<docking_msgs::WheelState>(docking_msgs::topics::kWheelState, 20);
    joint_state_pub_ = nh.advertise<sensor_msgs::JointState>(docking_msgs::topics::kJointStates, 20);
    cmd_sub_ = nh.subscribe(docking_msgs::topics::kCmdVel, 10, &OmniBaseNode::onCmdVel, this,
                            ros::TransportHints().tcpNoDelay());
    estop_sub_ = nh.subscribe(docking_msgs::topics::kEStop, 10, &OmniBaseNode::onEStop, this);
    release_srv_ = pnh.advertiseService("release_e_stop", &OmniBaseNode::onReleaseEStop, this);

    diagnostics_.setHardwareID("omni_base (" + backend_->describe() + ")");
    diagnostics_.add("Motor link", this, &OmniBaseNode::diagnoseLink);
    diagnostics_.add("Command", this, &OmniBaseNode::diagnoseCommand);
    diagnostics_.add("Encoders", this, &OmniBaseNode::diagnoseEncoders);

    timer_ = nh.createTimer(ros::Duration(1.0 / config_.control_rate_hz), &OmniBaseNode::onControlCycle, this);
    ROS_INFO("omni_base: %zu wheels, backend %s, %.0f Hz, cmd_vel timeout %.2f s, max wheel speed %.1f rad/s",
             config_.wheel_names.size(), backend_->describe().c_str(), config_.control_rate_hz,
             config_.controller.cmd_timeout_s, config_.controller.max_wheel_speed_rad_s);
  }

 private:
  void onCmdVel(const geometry_msgs::Twist::ConstPtr& msg) {
    const bool finite = std::isfinite(msg->linear.x) && std::isfinite(msg->linear.y) && std::isfinite(msg->linear.z) &&
                        std::isfinite(msg->angular.x) && std::isfinite(msg->angular.y) && std::isfinite(msg->angular.z);
    const Twist2D cmd = finite ? Twist2D{msg->linear.x, msg->linear.y, msg->angular.z} : Twist2D{NAN, NAN, NAN};
    switch (controller_.command(cmd, ros::Time::now().toSec())) {
      case CommandVerdict::kRejectedNonFinite:
        ROS_WARN_THROTTLE(1.0, "omni_base: rejected cmd_vel with a NaN or infinite component (%llu so far)",
                          static_cast<unsigned long long>(controller_.rejectedCommands()));
        break;
      case CommandVerdict::kIgnoredEStop:
        ROS_WARN_THROTTLE(2.0, "omni_base: cmd_vel ignored: e-stop latched (call %s to release)",
                          release_srv_.getService().c_str());
        break;
      case CommandVerdict::kAccepted:
        break;
    }
  }

  void onEStop(const std_msgs::Bool::ConstPtr& msg) {
    if (msg->data) {
      if (!controller_.eStopLatched()) {
        ROS_ERROR("omni_base: E-STOP engaged: wheels stopping; latched until %s is called",
                  release_srv_.getService().c_str());
      }
      controller_.engageEStop();
    }
  }

  bool onReleaseEStop(std_srvs::Trigger::Request&, std_srvs::Trigger::Response& res) {
    const bool was = controller_.eStopLatched();
    controller_.releaseEStop(ros::Time::now().toSec());
    res.success = true;
    res.message = was ? "e-stop released; the base moves on the next cmd_vel" : "e-stop was not latched";
    ROS_WARN("omni_base: %s", res.message.c_str());
    return true;
  }

  void onControlCycle(const ros::TimerEvent&) {
    const ros::Time now = ros::Time::now();
    // No reset on reconnect: the tracker tells a board that kept counting from one that rebooted.
    processEncoders(backend_->poll(now), now);

    const auto out = controller_.update(now.toSec(), backend_->linkUp());
    if (out.stop_reason != last_stop_reason_) {
      if (out.stop_reason == StopReason::kWatchdog) {
        ROS_WARN("omni_base: no cmd_vel for %.2f s: stopping", config_.controller.cmd_timeout_s);
      }
      last_stop_reason_ = out.stop_reason;
    }
    last_setpoints_ = out.wheel_rad_s;
    backend_->send(out.wheel_rad_s, !controller_.eStopLatched(), now);
    diagnostics_.update();
  }

  /// Every reading of the cycle goes through the tracker (a forged or reboot frame must be judged even
  /// when the next frame arrived in the same read); the odometry is published once, after the last
  /// reading that moved it, with that sample's velocities.
  void processEncoders(const std::vector<EncoderReading>& readings, const ros::Time& now) {
    const EncoderReading* counted = nullptr;
    EncoderTracker::Sample last_counted;
    for (const auto& reading : readings) {
      EncoderTracker::Sample sample = countEncoders(reading, now);
      if (!reportEncoderEvent(sample)) continue;
      // Motion is measured on the board's clock between accepted samples, so it is exact through bursts.
      odometry_.integrateDisplacement(kinematics_.forward(sample.delta_rad));
      counted = &reading;
      last_counted = std::move(sample);
    }
    if (!counted) return;
    const std::vector<double> wheel_velocity = last_counted.wheelVelocities();
    const Twist2D body_velocity = last_counted.dt_s > 0.0 ? kinematics_.forward(wheel_velocity) : Twist2D{};
    publishOdometry(*counted, body_velocity);
    publishWheelState(*counted, wheel_velocity);
  }

  /// One reading through the encoder tracker and the link doubt.
  EncoderTracker::Sample countEncoders(const EncoderReading& reading, const ros::Time& now) {
    if (reading.fault) {
      ROS_ERROR_THROTTLE(2.0, "omni_base: motor fault reported: %s", reading.fault_text.c_str());
    }
    EncoderTracker::Sample sample = encoders_.update(EncoderFrame{reading.counts, reading.source_time_ms, now.toSec()});
    link_doubt_.onSample(sample.event, sample.reason);
    if (!sample.reason.empty()) last_encoder_problem_ = sample.reason;
    return sample;
  }

  /// Logs the sample's event and acts on it; false when the sample moves nothing (held or rejected).
  bool reportEncoderEvent(const EncoderTracker::Sample& sample) {
    switch (sample.event) {
      case EncoderEvent::kRebootPending:
        // ENABLE to a board that did not reboot changes nothing; to one that did, it saves 0.1 s.
        ROS_WARN("omni_base: %s; odometry held", sample.reason.c_str());
        backend_->forceEnable();
        return false;
      case EncoderEvent::kBoardRebooted:
        ROS_ERROR("omni_base: %s; re-sending ENABLE", sample.reason.c_str());
        backend_->forceEnable();
        return true;
      case EncoderEvent::kRebootRefuted:
      case EncoderEvent::kRebaselined:
        ROS_ERROR("omni_base: %s", sample.reason.c_str());
        return true;
      case EncoderEvent::kRebootImplausible:
        ROS_ERROR("omni_base: encoder sample rejected: %s", sample.reason.c_str());
        return false;
      case EncoderEvent::kAccepted:
      case EncoderEvent::kBaseline:
        return true;
      case EncoderEvent::kWrongWheelCount:
      case EncoderEvent::kImplausibleJump:
      case EncoderEvent::kClockJumped:
        ROS_WARN_THROTTLE(1.0, "omni_base: encoder sample rejected: %s", sample.reason.c_str());
        return false;
    }
    return false;
  }

  void publishOdometry(const EncoderReading& reading, const Twist2D& velocity) {
    const Pose2D& pose = odometry_.pose();
    tf2::Quaternion q;
    q.setRPY(0.0, 0.0, pose.yaw);
    nav_msgs::Odometry odom;
    odom.header.stamp = reading.stamp;
    odom.header.frame_id = config_.odom_frame;
    odom.child_frame_id = config_.base_frame;
    odom.pose.pose.position.x = pose.x;
    odom.pose.pose.position.y = pose.y;
    odom.pose.pose.orientation.x = q.x();
    odom.pose.pose.orientation.y = q.y();
    odom.pose.pose.orientation.z = q.z();
    odom.pose.pose.orientation.w = q.w();
    odom.twist.twist.linear.x = velocity.vx;
    odom.twist.twist.linear.y = velocity.vy;
    odom.twist.twist.angular.z = velocity.wz;
    for (int i = 0; i < 6; ++i) {
      odom.pose.covariance[static_cast<std::size_t>(i * 7)] = config_.pose_covariance[static_cast<std::size_t>(i)];
      odom.twist.covariance[static_cast<std::size_t>(i * 7)] = config_.twist_covariance[static_cast<std::size_t>(i)];
    }
    odom_pub_.publish(odom);
    if (config_.publish_tf && reading.stamp != last_tf_stamp_) {
      geometry_msgs::TransformStamped tf;
      tf.header = odom.header;
      tf.child_frame_id = config_.base_frame;
      tf.transform.translation.x = pose.x;
      tf.transform.translation.y = pose.y;
      tf.transform.rotation = odom.pose.pose.orientation;
      tf_broadcaster_.sendTransform(tf);
      last_tf_stamp_ = reading.stamp;  // tf2 rejects repeated stamps for the same frame pair
    }
  }

  void publishWheelState(const EncoderReading& reading, const std::vector<double>& velocity) {
    docking_msgs::WheelState state;
    state.header.stamp = reading.stamp;
    state.header.frame_id = config_.base_frame;
    state.name = config_.wheel_names;
    state.setpoint = last_setpoints_;
    state.velocity = velocity;
    state.position = encoders_.positions();
    state.encoder_counts = reading.counts;
    wheel_state_pub_.publish(state);

    // The same angles for robot_state_publisher, which only reads sensor_msgs/JointState: the names are
    // the URDF's wheel joints (docking_description generates them from the same wheels/names).
    sensor_msgs::JointState joints;
    joints.header.stamp = reading.stamp;
    joints.name = state.name;
    joints.position = state.position;
    joints.velocity = state.velocity;
    joint_state_pub_.publish(joints);
  }

  void diagnoseCommand(diagnostic_updater::DiagnosticStatusWrapper& stat) {
    using diagnostic_msgs::DiagnosticStatus;
    switch (last_stop_reason_) {
      case StopReason::kNone: stat.summary(DiagnosticStatus::OK, "following cmd_vel"); break;
      case StopReason::kNoCommand: stat.summary(DiagnosticStatus::OK, "idle: no cmd_vel received yet"); break;
      case StopReason::kWatchdog: stat.summary(DiagnosticStatus::WARN, "cmd_vel timeout: stopped"); break;
      case StopReason::kEStop: stat.summary(DiagnosticStatus::WARN, "e-stop latched: stopped"); break;
      case StopReason::kLinkDown: stat.summary(DiagnosticStatus::ERROR, "motor link down: stopped"); break;
    }
    stat.add("seconds since cmd_vel", controller_.secondsSinceCommand(ros::Time::now().toSec()));
    stat.add("watchdog trips", controller_.watchdogTrips());
    stat.add("rejected non-finite commands", controller_.rejectedCommands());
    stat.add("e-stop latched", controller_.eStopLatched());
  }

  /// The backend's own status, made ERROR while the odometry is in doubt (LinkDoubt: a reboot claimed,
  /// refuted or confirmed, a re-baseline), at least once per doubt whatever the diagnostics rate.
  void diagnoseLink(diagnostic_updater::DiagnosticStatusWrapper& stat) {
    backend_->diagnose(stat);
    link_in_doubt_ = link_doubt_.report();
    if (link_in_doubt_) {
      stat.mergeSummaryf(diagnostic_msgs::DiagnosticStatus::ERROR, "odometry in doubt: %s", link_doubt_.cause().c_str());
    }
    stat.add("refused reboot claims", encoders_.refusedReboots());
  }

  void diagnoseEncoders(diagnostic_updater::DiagnosticStatusWrapper& stat) {
    using diagnostic_msgs::DiagnosticStatus;
    // The doubt as the Motor link task of the same update reported it.
    if (link_in_doubt_) {
      stat.summaryf(DiagnosticStatus::ERROR, "recovering: %s", link_doubt_.cause().c_str());
    } else if (encoders_.rejectedSamples() > reported_rejections_) {
      stat.summaryf(DiagnosticStatus::WARN, "implausible encoder samples rejected: %s", last_encoder_problem_.c_str());
    } else {
      stat.summary(DiagnosticStatus::OK, "encoders plausible");
    }
    reported_rejections_ = encoders_.rejectedSamples();
    stat.add("rejected samples", encoders_.rejectedSamples());
    stat.add("re-baselines", encoders_.rebaselines());
    stat.add("board reboots", encoders_.reboots());
  }

  NodeConfig config_;
  OmniKinematics kinematics_;
  BaseController controller_;
  EncoderTracker encoders_;
  LinkDoubt link_doubt_;
  bool link_in_doubt_{false};  ///< as the last diagnostics update reported it
  OdometryIntegrator odometry_;
  std::unique_ptr<MotorBackend> backend_;
  std::vector<double> last_setpoints_;
  StopReason last_stop_reason_{StopReason::kNoCommand};
  std::string last_encoder_problem_;
  std::uint64_t reported_rejections_{0};
  ros::Time last_tf_stamp_;

  ros::Publisher odom_pub_;
  ros::Publisher wheel_state_pub_;
  ros::Publisher joint_state_pub_;
  ros::Subscriber cmd_sub_;
  ros::Subscriber estop_sub_;
  ros::ServiceServer release_srv_;
  ros::Timer timer_;
  tf2_ros::TransformBroadcaster tf_broadcaster_;
  diagnostic_updater::Updater diagnostics_;
};

}  // namespace omni_base

int main(int argc, char** argv) {
  ros::init(argc, argv, "omni_base");
  return docking_settings::runNode([] {
    ros::NodeHandle nh;
    ros::NodeHandle pnh("~");
    omni_base::OmniBaseNode node(nh, pnh);
    ros::spin();
  });
}
