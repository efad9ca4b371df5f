// docking_sim_node: the thin ROS wrapper around docking_sim::Simulation. It owns time: steps the
// physics, publishes /clock, the three cameras, wheel encoders and ground truth, all in sim time.
#include <camera_calibration_parsers/parse.h>
#include <diagnostic_updater/diagnostic_updater.h>
#include <docking_msgs/WheelCommand.h>
#include <docking_msgs/WheelEncoders.h>
#include <docking_msgs/names.h>
#include <docking_settings/param_reader.h>
#include <geometry_msgs/TransformStamped.h>
#include <image_transport/image_transport.h>
#include <nav_msgs/Odometry.h>
#include <ros/ros.h>
#include <rosgraph_msgs/Clock.h>
#include <sensor_msgs/CameraInfo.h>
#include <sensor_msgs/Image.h>
#include <sensor_msgs/image_encodings.h>
#include <tf2_ros/static_transform_broadcaster.h>
#include <tf2_ros/transform_broadcaster.h>

#include <opencv2/core/utility.hpp>

#include <algorithm>
#include <array>
#include <cmath>
#include <memory>
#include <string>

#include "docking_sim/config_error.h"
#include "docking_sim/simulation.h"

namespace {

namespace names = docking_msgs;
using docking_sim::RobotModel;

/// A path or name the node cannot run without (missing, not a string or empty: ConfigError).
std::string requireName(const docking_settings::ParamReader& reader, const std::string& name) {
  const auto value = reader.require<std::string>(name);
  if (value.empty()) reader.invalid(name, "is empty (a path or name string)");
  return value;
}

geometry_msgs::Transform toTransform(const Eigen::Isometry3d& t) {
  geometry_msgs::Transform out;
  out.translation.x = t.translation().x();
  out.translation.y = t.translation().y();
  out.translation.z = t.translation().z();
  const Eigen::Quaterniond q(t.linear());
  out.rotation.x = q.x();
  out.rotation.y = q.y();
  out.rotation.z = q.z();
  out.rotation.w = q.w();
  return out;
}

geometry_msgs::Pose toPose(const Eigen::Isometry3d& t) {
  const auto tf = toTransform(t);
  geometry_msgs::Pose p;
  p.position.x = tf.translation.x;
  p.position.y = tf.translation.y;
  p.position.z = tf.translation.z;
  p.orientation = tf.rotation;
  return p;
}


class SimNode {
 public:
  SimNode(ros::NodeHandle& nh, ros::NodeHandle& pnh) : nh_(nh), image_transport_(nh), diagnostics_(nh, pnh) {
    sim_ = std::make_unique<docking_sim::Simulation>(simulationFiles(pnh));
    readRunParameters(pnh);
    advertise();
    if (publish_world_to_odom_) publishWorldToOdom();
    diagnostics_.setHardwareID("docking_sim");
    diagnostics_.add("Simulator", this, &SimNode::diagnose);
    const auto& sc = sim_->scenario();
    ROS_INFO("docking_sim: scenario '%s' (%s), lighting %s, seed %llu, duration %.0f s, real-time factor %.2f, "
             "cameras %.1f Hz (right stereo camera %.2f Hz), %d render thread(s)",
             sc.name.c_str(), sc.description.c_str(), sc.lighting.c_str(), static_cast<unsigned long long>(sc.seed),
             sc.duration_s, real_time_factor_, camera_rate_hz_, camera_rate_hz_ / right_camera_every_, render_threads_);
  }

  void run() {
    Schedule schedule(sim_->settings(), camera_rate_hz_);
    double last_clock_s = sim_->time();
    const ros::WallTime wall_start = ros::WallTime::now();
    ros::WallTime last_behind_warning = wall_start;
    while (ros::ok()) {
      const double next = schedule.next();
      if (real_time_factor_ > 0.0) keepRealTimeFactor(next, wall_start, &last_behind_warning);
      ros::spinOnce();  // wheel commands arrive at the sim time they are applied
      diagnostics_.update();
      sim_->advance(next - sim_->time());
      publishDueEvents(next, &schedule, &last_clock_s);
      if (scenarioFinished() && exit_at_end_) break;  // otherwise time keeps running, so that other nodes do not hang
    }
  }

 private:
  /// When each periodic event is next due: integer counters, so that stamps are exact multiples of their periods.
  struct Schedule {
    Schedule(const docking_sim::SimSettings& settings, double camera_rate_hz)
        : physics_dt(1.0 / settings.physics_rate_hz),
          camera_dt(1.0 / camera_rate_hz),
          encoder_dt(1.0 / settings.encoder_rate_hz),
          tf_dt(1.0 / settings.truth_tf_rate_hz) {}
    double next() const {
      return std::min({physics_n * physics_dt, camera_n * camera_dt, encoder_n * encoder_dt, tf_n * tf_dt});
    }
    double physics_dt, camera_dt, encoder_dt, tf_dt;
    long physics_n = 1, camera_n = 1, encoder_n = 1, tf_n = 1;
  };

  static docking_sim::SimulationFiles simulationFiles(const ros::NodeHandle& pnh) {
    const docking_settings::ParamReader reader(pnh);
    docking_sim::SimulationFiles files;
    files.sim_config = requireName(reader, "sim_config");
    files.target_config = requireName(reader, "target_config");
    files.robot_config = requireName(reader, "robot_config");
    files.omni_base_config = requireName(reader, "omni_base_config");
    std::string scenario_file;
    if (pnh.getParam("scenario_file", scenario_file) && !scenario_file.empty()) {
      files.scenario = scenario_file;
    } else {
      files.scenario = requireName(reader, "scenario_dir") + "/" + requireName(reader, "scenario") + ".yaml";
    }
    return files;
  }

  /// The node's own parameters (rates, threads, flags); sim.yaml's values where absent.
  void readRunParameters(const ros::NodeHandle& pnh) {
    const auto& settings = sim_->settings();
    const docking_settings::ParamReader reader(pnh);
    real_time_factor_ = reader.optional("real_time_factor", settings.real_time_factor);
    camera_rate_hz_ = reader.optional("camera_rate_hz", settings.camera_rate_hz);
    if (!std::isfinite(real_time_factor_) || real_time_factor_ < 0.0) {
      reader.invalid("real_time_factor", "must be >= 0 (0 = as fast as possible)");
    }
    if (!std::isfinite(camera_rate_hz_) || camera_rate_hz_ <= 0.0 || camera_rate_hz_ > 200.0) {
      reader.invalid("camera_rate_hz", "must be within (0, 200]");
    }
    render_threads_ = reader.optional("render_threads", settings.render_threads);
    if (render_threads_ < 1 || render_threads_ > 3) {
      reader.invalid("render_threads", "must be 1, 2 or 3");
    }
    const double right_rate_hz = reader.optional("stereo_right_rate_hz", settings.stereo_right_rate_hz);
    if (!std::isfinite(right_rate_hz) || right_rate_hz < 0.0) {
      reader.invalid("stereo_right_rate_hz", "must be >= 0 (0 = camera_rate_hz)");
    }
    right_camera_every_ = rightCameraEvery(camera_rate_hz_, right_rate_hz);
    exit_at_end_ = reader.optional("exit_at_end", true);
    publish_world_to_odom_ = reader.optional("publish_world_to_odom", true);
  }

  /// Camera publishers (camera info straight from the calibration files the robot uses, through
  /// camera_calibration_parsers), clock, encoders, truth, and the wheel command subscriber.
  void advertise() {
    const char* image_topics[3] = {names::topics::kStereoLeftImageRaw, names::topics::kStereoRightImageRaw,
                                   names::topics::kIrImageRaw};
    for (int i = 0; i < 3; ++i) {
      const auto& mount = sim_->robot().cameras[static_cast<std::size_t>(i)];
      std::string camera_name;
      if (!camera_calibration_parsers::readCalibration(mount.calibration_file, camera_name, infos_[i])) {
        throw docking_sim::ConfigError(mount.calibration_file, "", "camera_calibration_parsers cannot read it");
      }
      infos_[i].header.frame_id = mount.image_frame_id;
      // Queue 5: when rendering falls behind real time (a busy machine, motion-blur sub-frames), the
      // node catches up in a burst of frames; 2 dropped some of them on their way to slow subscribers.
      camera_pubs_[i] = image_transport_.advertiseCamera(image_topics[i], kImageQueueSize);
    }
    clock_pub_ = nh_.advertise<rosgraph_msgs::Clock>("/clock", 10);
    encoder_pub_ = nh_.advertise<docking_msgs::WheelEncoders>(names::topics::kWheelEncoders, 10);
    truth_left_pub_ = nh_.advertise<nav_msgs::Odometry>(names::topics::kTruthStereoLeft, 10);
    truth_ir_pub_ = nh_.advertise<nav_msgs::Odometry>(names::topics::kTruthIr, 10);
    truth_chaser_pub_ = nh_.advertise<nav_msgs::Odometry>(names::topics::kTruthChaserOdom, 10);
    command_sub_ = nh_.subscribe(names::topics::kWheelCommand, 10, &SimNode::onWheelCommand, this);
  }

  /// odom starts where the chaser starts, so rviz can show odometry and truth in one tree.
  void publishWorldToOdom() {
    geometry_msgs::TransformStamped t;
    t.header.stamp = ros::Time(kTimeOffsetS);
    t.header.frame_id = names::frames::kWorld;
    t.child_frame_id = names::frames::kOdom;
    t.transform = toTransform(sim_->worldTChaser());
    static_broadcaster_.sendTransform(t);
  }

  /// Sleeps until sim time `next` is due on the wall clock; warns (every 10 s at most) when behind.
  void keepRealTimeFactor(double next, const ros::WallTime& wall_start, ros::WallTime* last_behind_warning) const {
    const ros::WallTime due = wall_start + ros::WallDuration(next / real_time_factor_);
    const ros::WallTime now = ros::WallTime::now();
    if (due > now) {
      (due - now).sleep();
    } else if ((now - due).toSec() > 0.5 && (now - *last_behind_warning).toSec() > 10.0) {
      ROS_WARN("docking_sim: %.1f s behind the requested real-time factor %.2f (rendering is the bottleneck)",
               (now - due).toSec() * real_time_factor_, real_time_factor_);
      *last_behind_warning = now;
    }
  }

  /// At sim time `next`: /clock (with every stamped message, and at least every kMaxClockGapS), then
  /// the encoders, truth tf and cameras that are due; advances their counters.
  void publishDueEvents(double next, Schedule* s, double* last_clock_s) {
    const ros::Time stamp(sim_->time() + kTimeOffsetS);
    const double eps = 1e-9;
    const bool encoders_due = s->encoder_n * s->encoder_dt <= next + eps;
    const bool tf_due = s->tf_n * s->tf_dt <= next + eps;
    const bool cameras_due = s->camera_n * s->camera_dt <= next + eps;
    if (encoders_due || tf_due || cameras_due || sim_->time() - *last_clock_s >= kMaxClockGapS - eps) {
      publishClock(stamp);
      *last_clock_s = sim_->time();
    }
    if (s->physics_n * s->physics_dt <= next + eps) ++s->physics_n;
    if (encoders_due) {
      ++s->encoder_n;
      publishEncoders(stamp);
    }
    if (tf_due) {
      ++s->tf_n;
      publishTruthTf(stamp);
    }
    if (cameras_due) {
      publishCameras(stamp, s->camera_n);
      ++s->camera_n;
    }
  }

  /// True from the moment the scenario's duration has passed (logged once).
  bool scenarioFinished() {
    const double duration = sim_->scenario().duration_s;
    if (duration > 0.0 && sim_->time() >= duration && !finished_) {
      finished_ = true;
      ROS_INFO("docking_sim: scenario '%s' finished after %.1f s of sim time", sim_->scenario().name.c_str(),
               sim_->time());
      return true;
    }
    return false;
  }

  static constexpr uint32_t kImageQueueSize = 5;

  /// The right camera renders every n-th frame of the cameras' clock: the largest n whose rate still
  /// reaches the one asked (0 = every frame). Its stamps stay the left camera's, so stereo pairs match.
  static long rightCameraEvery(double camera_rate_hz, double right_rate_hz) {
    if (right_rate_hz <= 0.0 || right_rate_hz >= camera_rate_hz) return 1;
    return std::max(1L, static_cast<long>(std::floor(camera_rate_hz / right_rate_hz + 1e-9)));
  }
  // Sim time 0 would read as "no time yet" to ROS nodes: the published clock starts at this offset.
  static constexpr double kTimeOffsetS = 1.0;
  // /clock goes out with every stamped message (encoders, truth tf, cameras: no node receives a stamp
  // ahead of its clock) and otherwise at least this often, not at every physics step: every node of the
  // stack receives each /clock message (a wakeup and a deserialisation each, ~15 nodes), and 98 Hz
  // instead of 215 halves that. 10 ms keeps the stack's sim-time timers (50 Hz and slower) on their
  // periods (docs/PERFORMANCE.md).
  static constexpr double kMaxClockGapS = 0.01;

  void publishClock(const ros::Time& stamp) {
    rosgraph_msgs::Clock clock;
    clock.clock = stamp;
    clock_pub_.publish(clock);
  }

  void diagnose(diagnostic_updater::DiagnosticStatusWrapper& status) {
    // Achieved real-time factor since the last report.
    const ros::WallTime now = ros::WallTime::now();
    const double wall = (now - last_diag_wall_).toSec();
    const double achieved = wall > 0 ? (sim_->time() - last_diag_sim_) / wall : 0.0;
    last_diag_wall_ = now;
    last_diag_sim_ = sim_->time();
    if (real_time_factor_ > 0 && achieved < 0.8 * real_time_factor_) {
      status.summary(diagnostic_msgs::DiagnosticStatus::WARN, "slower than the requested real-time factor");
    } else {
      status.summary(diagnostic_msgs::DiagnosticStatus::OK, "running");
    }
    status.add("scenario", sim_->scenario().name);
    status.add("lighting", sim_->scenario().lighting);
    status.add("sim time (s)", sim_->time());
    status.add("requested real-time factor", real_time_factor_);
    status.add("achieved real-time factor", achieved);
    const char* keys[3] = {"render stereo_left (ms CPU)", "render stereo_right (ms CPU)", "render ir (ms CPU)"};
    for (int i = 0; i < 3; ++i) status.add(keys[i], render_ms_[i]);
  }

  void onWheelCommand(const docking_msgs::WheelCommand::ConstPtr& msg) {
    using docking_sim::CommandResult;
    const CommandResult result = sim_->wheelCommand(msg->enable, msg->velocity);
    if (result == CommandResult::kRejectedNonFinite) {
      ROS_WARN_THROTTLE(1.0, "docking_sim: rejected a wheel command with NaN/inf speeds; wheels stop");
    } else if (result == CommandResult::kRejectedWrongSize) {
      ROS_WARN_THROTTLE(1.0, "docking_sim: rejected a wheel command with %zu speeds (the base has %zu wheels)",
                        msg->velocity.size(), sim_->chaser().wheelCount());
    }
  }

  void publishEncoders(const ros::Time& stamp) {
    docking_msgs::WheelEncoders msg;
    msg.header.stamp = stamp;
    msg.header.frame_id = names::frames::kBaseLink;
    msg.counts = sim_->chaser().encoderCounts();
    msg.motors_enabled = sim_->chaser().motorsEnabled();
    msg.fault = false;
    encoder_pub_.publish(msg);
  }

  void publishTruthTf(const ros::Time& stamp) {
    geometry_msgs::TransformStamped chaser, target;
    chaser.header.stamp = target.header.stamp = stamp;
    chaser.header.frame_id = target.header.frame_id = names::frames::kWorld;
    chaser.child_frame_id = names::frames::kChaserTruth;
    target.child_frame_id = names::frames::kTargetTruth;
    chaser.transform = toTransform(sim_->worldTChaser());
    target.transform = toTransform(sim_->worldTPort());
    tf_broadcaster_.sendTransform({chaser, target});

    nav_msgs::Odometry odom;
    odom.header.stamp = stamp;
    odom.header.frame_id = names::frames::kWorld;
    odom.child_frame_id = names::frames::kChaserTruth;
    odom.pose.pose = toPose(sim_->worldTChaser());
    const auto twist = sim_->chaser().twist();  // body frame (child), as nav_msgs/Odometry wants
    odom.twist.twist.linear.x = twist.vx;
    odom.twist.twist.linear.y = twist.vy;
    odom.twist.twist.angular.z = twist.wz;
    truth_chaser_pub_.publish(odom);
  }

  void publishCameras(const ros::Time& stamp, long frame_index) {
    std::array<bool, 3> wanted{};
    for (int i = 0; i < 3; ++i) {
      wanted[static_cast<std::size_t>(i)] = camera_pubs_[i].getNumSubscribers() > 0;  // only what someone watches
    }
    if (frame_index % right_camera_every_ != 0) wanted[RobotModel::kStereoRight] = false;
    const auto frames = sim_->renderCameras(wanted, render_threads_);
    for (int i = 0; i < 3; ++i) {
      if (frames[static_cast<std::size_t>(i)] == nullptr) continue;
      const auto& t = sim_->renderer(i).lastTiming();
      render_ms_[i] = 0.9 * render_ms_[i] + 0.1 * (t.rasterize_ms + t.defocus_ms + t.distort_ms + t.effects_ms);
      publishFrame(i, *frames[static_cast<std::size_t>(i)], stamp);
    }
    publishCameraTruth(RobotModel::kStereoLeft, truth_left_pub_, stamp);
    publishCameraTruth(RobotModel::kIr, truth_ir_pub_, stamp);
  }

  void publishFrame(int camera, const cv::Mat& frame, const ros::Time& stamp) {
    const auto& mount = sim_->robot().cameras[static_cast<std::size_t>(camera)];
    sensor_msgs::ImagePtr image = boost::make_shared<sensor_msgs::Image>();
    image->header.stamp = stamp;
    image->header.frame_id = mount.image_frame_id;
    image->height = static_cast<uint32_t>(frame.rows);
    image->width = static_cast<uint32_t>(frame.cols);
    image->encoding = frame.channels() == 3 ? sensor_msgs::image_encodings::BGR8 : sensor_msgs::image_encodings::MONO8;
    image->is_bigendian = 0;
    image->step = static_cast<uint32_t>(frame.cols * frame.channels());
    image->data.resize(image->step * image->height);
    for (int r = 0; r < frame.rows; ++r) {
      std::copy(frame.ptr<uchar>(r), frame.ptr<uchar>(r) + image->step, image->data.begin() + r * image->step);
    }
    sensor_msgs::CameraInfoPtr info = boost::make_shared<sensor_msgs::CameraInfo>(infos_[camera]);
    info->header = image->header;
    camera_pubs_[camera].publish(image, info);
  }

  void publishCameraTruth(int camera, ros::Publisher& pub, const ros::Time& stamp) {
    const auto truth = sim_->truthInCamera(camera);
    nav_msgs::Odometry odom;
    odom.header.stamp = stamp;
    odom.header.frame_id = sim_->robot().cameras[static_cast<std::size_t>(camera)].frame_id;
    odom.child_frame_id = names::frames::kTarget;
    odom.pose.pose = toPose(truth.camera_T_port);
    // Velocity of the port relative to the camera, in the camera frame (as TargetEstimate's twist).
    odom.twist.twist.linear.x = truth.linear_m_s.x();
    odom.twist.twist.linear.y = truth.linear_m_s.y();
    odom.twist.twist.linear.z = truth.linear_m_s.z();
    odom.twist.twist.angular.x = truth.angular_rad_s.x();
    odom.twist.twist.angular.y = truth.angular_rad_s.y();
    odom.twist.twist.angular.z = truth.angular_rad_s.z();
    pub.publish(odom);
  }

  ros::NodeHandle nh_;
  image_transport::ImageTransport image_transport_;
  std::unique_ptr<docking_sim::Simulation> sim_;
  double real_time_factor_{1.0};
  double camera_rate_hz_{30.0};
  int render_threads_{2};
  long right_camera_every_{1};
  bool exit_at_end_{true};
  bool finished_{false};
  bool publish_world_to_odom_{true};
  std::array<sensor_msgs::CameraInfo, 3> infos_;
  std::array<image_transport::CameraPublisher, 3> camera_pubs_;
  ros::Publisher clock_pub_, encoder_pub_, truth_left_pub_, truth_ir_pub_, truth_chaser_pub_;
  ros::Subscriber command_sub_;
  diagnostic_updater::Updater diagnostics_;
  std::array<double, 3> render_ms_{{0.0, 0.0, 0.0}};
  ros::WallTime last_diag_wall_{ros::WallTime::now()};
  double last_diag_sim_{0.0};
  tf2_ros::TransformBroadcaster tf_broadcaster_;
  tf2_ros::StaticTransformBroadcaster static_broadcaster_;
};

}  // namespace

int main(int argc, char** argv) {
  ros::init(argc, argv, "docking_sim");
  ros::NodeHandle nh;
  ros::NodeHandle pnh("~");
  cv::setNumThreads(1);  // one core for rendering; perception gets the rest
  try {
    SimNode node(nh, pnh);
    node.run();
  } catch (const std::exception& e) {
    ROS_FATAL("docking_sim: %s", e.what());
    return 1;
  }
  return 0;
}
