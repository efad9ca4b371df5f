// arbiter: a thin node around SourceArbiter. Subscribes the three estimators' TargetEstimates, lets
// the core choose one, re-expresses it in `output_frame` with tf2, and publishes it as the FUSED
// estimate, as pose and twist, as tf output_frame -> target, and its choice on a status topic and in
// diagnostics. Parameters: config/arbiter.yaml (see README.md).
#include <algorithm>
#include <array>
#include <cmath>
#include <cstdio>
#include <initializer_list>
#include <map>
#include <memory>
#include <optional>
#include <stdexcept>
#include <string>

#include <diagnostic_updater/diagnostic_updater.h>
#include <docking_perception/ArbiterConfig.h>
#include <dynamic_reconfigure/server.h>
#include "docking_msgs/latency_window.h"
#include "docking_settings/param_reader.h"
#include "docking_settings/reconfigure.h"
#include "docking_settings/ros_loader.h"
#include "docking_settings/run_node.h"
#include <docking_msgs/TargetEstimate.h>
#include <docking_msgs/estimate_check_msg.h>
#include <docking_msgs/names.h>
#include <geometry_msgs/PoseWithCovarianceStamped.h>
#include <geometry_msgs/TwistWithCovarianceStamped.h>
#include <ros/ros.h>
#include <std_msgs/String.h>
#include <tf2_eigen/tf2_eigen.h>
#include <tf2_ros/buffer.h>
#include <tf2_ros/transform_broadcaster.h>
#include <tf2_ros/transform_listener.h>

#include "docking_perception/arbiter/input_silence.h"
#include "docking_perception/arbiter/frame_change.h"
#include "docking_perception/arbiter/source_arbiter.h"

namespace docking_perception {
namespace arbiter {
namespace {

/// The longest wait for a camera's mount transform per estimate, s: the mounts are robot.yaml's static
/// transforms, there from start-up or not at all; 20 ms keeps a missing one from stalling the node.
constexpr double kMountTransformWaitS = 0.02;

/// The node's settings: the declared defaults with the parameter server's values (config/arbiter.yaml).
ArbiterNodeSettings loadSettings(const ros::NodeHandle& pnh) {
  ArbiterNodeSettings settings;
  docking_settings::loadSettings(pnh, settings);
  docking_settings::warnUnknownKeys(pnh, settings);
  docking_settings::ParamReader(pnh).validated([&] { validate(settings.core); });
  return settings;
}

Matrix6d toMatrix(const boost::array<double, 36>& a) {
  Matrix6d m;
  for (int r = 0; r < 6; ++r)
    for (int c = 0; c < 6; ++c) m(r, c) = a[static_cast<std::size_t>(r * 6 + c)];
  return m;
}

void fromMatrix(const Matrix6d& m, boost::array<double, 36>& a) {
  for (int r = 0; r < 6; ++r)
    for (int c = 0; c < 6; ++c) a[static_cast<std::size_t>(r * 6 + c)] = m(r, c);
}

/// `msg` must already be in the output frame: its pose and twist become the summary's common-frame
/// pose and twist (for the consistency check).
EstimateSummary summarize(const docking_msgs::TargetEstimate& msg, Source source) {
  EstimateSummary s;
  s.source = source;
  s.stamp_s = msg.header.stamp.toSec();
  s.valid = msg.valid;
  s.position_valid = msg.position_valid;
  s.orientation_valid = msg.orientation_valid;
  s.range_m = msg.range_m;
  s.feature_inliers = msg.feature_inliers;
  s.reprojection_error_px = msg.reprojection_error_px;
  s.status = msg.status;
  const auto& p = msg.pose.pose.position;
  const auto& q = msg.pose.pose.orientation;
  const auto& v = msg.twist.twist.linear;
  const auto& w = msg.twist.twist.angular;
  const auto finite = [](std::initializer_list<double> values) {
    for (double x : values)
      if (!std::isfinite(x)) return false;
    return true;
  };
  s.values_finite = (!msg.position_valid || finite({p.x, p.y, p.z})) &&
                    (!msg.orientation_valid || finite({q.x, q.y, q.z, q.w})) &&
                    (!msg.twist_valid || finite({v.x, v.y, v.z, w.x, w.y, w.z}));
  if (msg.valid && msg.position_valid) {
    PoseWithCovariance3 pose;
    pose.position = Eigen::Vector3d(p.x, p.y, p.z);
    pose.orientation = Eigen::Quaterniond(q.w, q.x, q.y, q.z);
    pose.covariance = toMatrix(msg.pose.covariance);
    s.pose = pose;
  }
  if (msg.valid && msg.twist_valid) {
    TwistWithCovariance3 twist;
    twist.linear = Eigen::Vector3d(v.x, v.y, v.z);
    twist.angular = Eigen::Vector3d(w.x, w.y, w.z);
    twist.covariance = toMatrix(msg.twist.covariance);
    s.twist = twist;
  }
  return s;
}

class ArbiterNode {
 public:
  ArbiterNode(ros::NodeHandle& nh, ros::NodeHandle& pnh, const ArbiterNodeSettings& settings)
      : arbiter_(settings.core), tf_listener_(tf_buffer_), diagnostics_(nh, pnh) {
    output_frame_ = settings.output_frame;
    if (output_frame_.empty()) docking_settings::ParamReader(pnh).invalid("output_frame", "is empty");
    silence_ = std::make_unique<InputSilence>(settings.sources_silent_timeout_s);
    const double status_rate_hz = settings.status_rate_hz;

    estimate_pub_ = nh.advertise<docking_msgs::TargetEstimate>(docking_msgs::topics::kTargetEstimate, 10);
    pose_pub_ = nh.advertise<geometry_msgs::PoseWithCovarianceStamped>(docking_msgs::topics::kTargetPose, 10);
    twist_pub_ = nh.advertise<geometry_msgs::TwistWithCovarianceStamped>(docking_msgs::topics::kTargetTwist, 10);
    status_pub_ = nh.advertise<std_msgs::String>(docking_msgs::topics::kArbiterStatus, 10, true);

    subscribe(nh, docking_msgs::topics::kDisparityEstimate, Source::kDisparity);
    subscribe(nh, docking_msgs::topics::kMonoVisibleEstimate, Source::kMonoVisible);
    subscribe(nh, docking_msgs::topics::kMonoIrEstimate, Source::kMonoIr);

    // Live tuning; the server starts from the values loaded above (same parameter names).
    reconfigure_server_ = std::make_unique<dynamic_reconfigure::Server<docking_perception::ArbiterConfig>>(pnh);
    reconfigure_server_->setCallback(
        [this](docking_perception::ArbiterConfig& cfg, std::uint32_t) { onReconfigure(cfg); });

    diagnostics_.setHardwareID("none");
    diagnostics_.add("target source", this, &ArbiterNode::diagnose);
    timer_ = nh.createTimer(ros::Duration(1.0 / status_rate_hz), &ArbiterNode::onTimer, this);
  }

 private:
  void onReconfigure(docking_perception::ArbiterConfig& cfg) {
    dynamic_reconfigure::Config message;
    cfg.__toMessage__(message);
    arbiter::ArbiterConfig c = arbiter_.config();
    docking_settings::applyReconfigure(message, c);
    try {
      arbiter_.reconfigure(c);
    } catch (const std::invalid_argument& e) {
      ROS_ERROR("arbiter: reconfigure refused (%s); keeping the previous values", e.what());
      // Show the values in force, not the refused ones (the server publishes what the callback leaves).
      dynamic_reconfigure::Config kept = docking_settings::toReconfigure(arbiter_.config());
      cfg.__fromMessage__(kept);
    }
  }

  void subscribe(ros::NodeHandle& nh, const char* topic, Source source) {
    // A boost::function of the event type: a lambda given to subscribe<M>() is wrapped as a callback of
    // the message pointer, and the event built from that pointer names no publisher.
    const boost::function<void(const ros::MessageEvent<docking_msgs::TargetEstimate const>&)> callback =
        [this, source](const ros::MessageEvent<docking_msgs::TargetEstimate const>& event) {
          onEstimateEvent(event, source);
        };
    // TCP_NODELAY: an estimate is a small message on the way to cmd_vel; Nagle's algorithm would hold
    // one back until the previous one is acknowledged (tens of ms on a delayed ACK).
    subscribers_.push_back(nh.subscribe<docking_msgs::TargetEstimate>(topic, 10, callback, ros::VoidConstPtr(),
                                                                       ros::TransportHints().tcpNoDelay()));
  }

  // Nothing an estimate contains may end the node: whatever the algorithm code throws drops that
  // estimate, with a diagnostic, and the node goes on.
  void onEstimateEvent(const ros::MessageEvent<docking_msgs::TargetEstimate const>& event, Source source) {
    try {
      onEstimate(event.getConstMessage(), source, event.getPublisherName());
    } catch (const std::exception& e) {
      recordRejection(event.getPublisherName(), source, "exception", e.what());
    }
  }

  /// Counts a refused estimate by its code, keeps who sent it and why for the diagnostics, and warns
  /// (throttled). No other state changes.
  void recordRejection(const std::string& publisher, Source source, const std::string& code, const std::string& why) {
    ++rejections_by_code_[code];
    last_rejection_ = std::string(sourceName(source)) + " estimate from " + publisher + ": " + code + " (" + why + ")";
    ROS_WARN_THROTTLE(2.0, "arbiter: dropped a %s estimate from %s: %s: %s", sourceName(source), publisher.c_str(),
                      code.c_str(), why.c_str());
  }

  void onEstimate(const docking_msgs::TargetEstimateConstPtr& msg, Source source, const std::string& publisher) {
    if (msg->source != static_cast<std::uint8_t>(source)) {
      ROS_WARN_THROTTLE(5.0, "arbiter: estimate on the %s topic says source %u; treated as %s", sourceName(source),
                        msg->source, sourceName(source));
    }
    // Numbers first (a zero quaternion, a NaN): refused whole, before any state or tf look-up.
    const auto problem = docking_msgs::checks::checkEstimate(*msg);
    if (problem != docking_msgs::checks::EstimateProblem::kNone) {
      recordRejection(publisher, source, docking_msgs::checks::estimateProblemName(problem), "numbers refused");
      return;
    }
    const double now_s = ros::Time::now().toSec();
    // The stamp against now before the tf look-up, which would wait kMountTransformWaitS for a future one.
    const auto stamp_problem =
        docking_msgs::checks::checkStamp(msg->header.stamp.toSec(), now_s, docking_msgs::checks::kStampLimits);
    if (stamp_problem != docking_msgs::checks::StampProblem::kNone) {
      const OfferResult refused = arbiter_.offer(summarize(*msg, source), now_s);  // counted, state untouched
      recordRejection(publisher, source, offerProblemName(refused.problem), refused.reason);
      return;
    }
    silence_->noteArrival(now_s);  // a well-formed message: its estimator is alive, whatever it says
    // Every valid estimate is brought into the output frame on arrival, so that the consistency
    // check compares the sources in one frame and the chosen one is published without a second look-up.
    std::optional<docking_msgs::TargetEstimate> in_output_frame;
    EstimateSummary summary;
    if (msg->valid) {
      in_output_frame = toOutputFrame(*msg, source);
      if (in_output_frame) {
        summary = summarize(*in_output_frame, source);
      } else {  // unusable without the mount transform: kept as the source's latest word, invalid
        summary = summarize(*msg, source);
        summary.pose.reset();
        summary.twist.reset();
        summary.valid = false;
        summary.status = "no transform into " + output_frame_;
      }
    } else {
      summary = summarize(*msg, source);
    }
    const OfferResult offered = arbiter_.offer(summary, now_s);
    if (!offered.accepted) {
      recordRejection(publisher, source, offerProblemName(offered.problem), offered.reason);
      return;
    }
    latest_msgs_[static_cast<std::size_t>(source)] = in_output_frame;
    decideAndPublish(false);
  }

  void onTimer(const ros::TimerEvent&) {
    try {
      decideAndPublish(true);
    } catch (const std::exception& e) {
      ROS_ERROR_THROTTLE(5.0, "arbiter: decision failed: %s", e.what());
    }
    diagnostics_.update();
  }

  // Called on every estimate and on the timer; `periodic` re-publishes "nothing valid" at the timer's
  // rate so that subscribers see the loss even when no estimator publishes at all.
  void decideAndPublish(bool periodic) {
    const double now_s = ros::Time::now().toSec();
    if (silence_->silent(now_s)) {
      publishSilence(now_s, periodic);
      return;
    }
    was_silent_ = false;
    const Decision d = arbiter_.decide(now_s);
    const bool changed = d.valid != last_decision_.valid || d.source != last_decision_.source ||
                         d.reason != last_decision_.reason;
    last_decision_ = d;
    if (changed || periodic) {
      std_msgs::String status;
      status.data = std::string(d.valid ? sourceName(d.source) : "none") + " (" + decisionCodeName(d.code) +
                    "): " + d.reason;
      status_pub_.publish(status);
    }
    const auto& chosen = latest_msgs_[static_cast<std::size_t>(d.source)];
    if (d.valid && d.is_new && chosen) {
      publishChosen(*chosen, d.source);
    } else if (!d.valid && (periodic || changed)) {
      publishNothing(std::string(decisionCodeName(d.code)) + ": " + d.reason);
    }
  }

  std::string silenceText(double now_s) const {
    if (!silence_->heardAny()) return "no estimator has published yet";
    char text[96];
    std::snprintf(text, sizeof(text), "no estimator has published for %.2f s", silence_->silentFor(now_s));
    return text;
  }

  /// No estimator talks (perception stalled or gone): "nothing valid" with its own code, so that the
  /// planner stops and waits instead of searching.
  void publishSilence(double now_s, bool periodic) {
    if (!was_silent_) {
      // Before the first estimate this is start-up (perception loading, a replay's clock jumping to the
      // bag's start), not a fault: a warning. Silence after estimates have come is the fault.
      if (silence_->heardAny()) {
        ROS_ERROR("arbiter: %s (perception stalled or gone)", silenceText(now_s).c_str());
      } else {
        ROS_WARN("arbiter: %s (waiting for perception)", silenceText(now_s).c_str());
      }
    }
    const bool changed = !was_silent_;
    was_silent_ = true;
    if (!(changed || periodic)) return;
    std_msgs::String status;
    status.data = "none (sources_silent): no estimator has published";
    status_pub_.publish(status);
    publishNothing("sources_silent: no estimator has published", docking_msgs::TargetEstimate::REJECT_SOURCES_SILENT);
  }

  void publishNothing(const std::string& reason,
                      std::uint8_t reject_reason = docking_msgs::TargetEstimate::REJECT_NONE) {
    docking_msgs::TargetEstimate out;
    out.header.stamp = ros::Time::now();
    out.header.frame_id = output_frame_;
    out.source = docking_msgs::TargetEstimate::SOURCE_FUSED;
    out.selected_source = docking_msgs::TargetEstimate::SOURCE_FUSED;
    out.valid = false;
    out.status = reason;
    out.reject_reason = reject_reason;
    estimate_pub_.publish(out);
  }

  /// The estimate re-expressed in output_frame_ (pose, twist, covariances, range); nothing when the
  /// camera's transform is not available.
  std::optional<docking_msgs::TargetEstimate> toOutputFrame(const docking_msgs::TargetEstimate& in, Source source) {
    Eigen::Isometry3d out_from_in;
    try {
      out_from_in = tf2::transformToEigen(
          tf_buffer_.lookupTransform(output_frame_, in.header.frame_id, in.header.stamp,
                                     ros::Duration(kMountTransformWaitS)));
    } catch (const tf2::TransformException& e) {
      ++tf_failures_;
      last_tf_error_ = e.what();
      ROS_WARN_THROTTLE(2.0, "arbiter: cannot bring the %s estimate from '%s' into '%s': %s", sourceName(source),
                        in.header.frame_id.c_str(), output_frame_.c_str(), e.what());
      return std::nullopt;
    }
    PoseWithCovariance3 pose_in;
    pose_in.position = Eigen::Vector3d(in.pose.pose.position.x, in.pose.pose.position.y, in.pose.pose.position.z);
    const auto& q = in.pose.pose.orientation;
    pose_in.orientation = Eigen::Quaterniond(q.w, q.x, q.y, q.z);
    // A claimed orientation is a unit quaternion (checked on arrival); an unclaimed one is undefined:
    // identity keeps the message well-formed, and orientation_valid stays false.
    if (!in.orientation_valid) pose_in.orientation = Eigen::Quaterniond::Identity();
    pose_in.orientation.normalize();
    pose_in.covariance = toMatrix(in.pose.covariance);
    TwistWithCovariance3 twist_in;
    twist_in.linear = Eigen::Vector3d(in.twist.twist.linear.x, in.twist.twist.linear.y, in.twist.twist.linear.z);
    twist_in.angular = Eigen::Vector3d(in.twist.twist.angular.x, in.twist.twist.angular.y, in.twist.twist.angular.z);
    twist_in.covariance = toMatrix(in.twist.covariance);

    const PoseWithCovariance3 pose_out = changeFrame(out_from_in, pose_in);
    const TwistWithCovariance3 twist_out = changeFrameRigidMount(out_from_in.rotation(), twist_in);

    docking_msgs::TargetEstimate out = in;
    out.header.frame_id = output_frame_;
    out.pose.pose.position = tf2::toMsg(pose_out.position);
    out.pose.pose.orientation = tf2::toMsg(pose_out.orientation);
    fromMatrix(pose_out.covariance, out.pose.covariance);
    tf2::toMsg(twist_out.linear, out.twist.twist.linear);
    tf2::toMsg(twist_out.angular, out.twist.twist.angular);
    fromMatrix(twist_out.covariance, out.twist.covariance);
    out.range_m = pose_out.position.norm();  // from the output camera, not the source camera
    return out;
  }

  /// Publishes an estimate already in output_frame_ as the FUSED one (estimate, pose, twist, tf).
  void publishChosen(const docking_msgs::TargetEstimate& in_output_frame, Source source) {
    docking_msgs::TargetEstimate out = in_output_frame;
    out.source = docking_msgs::TargetEstimate::SOURCE_FUSED;
    out.selected_source = static_cast<std::uint8_t>(source);
    out.status.clear();  // TargetEstimate: empty when valid; the choice's reason is on the status topic
    estimate_pub_.publish(out);
    ++published_;
    latency_.add((ros::Time::now() - out.header.stamp).toSec());  // the stamp is the source image's

    geometry_msgs::PoseWithCovarianceStamped pose_msg;
    pose_msg.header = out.header;
    pose_msg.pose = out.pose;
    pose_pub_.publish(pose_msg);
    if (out.twist_valid) {
      geometry_msgs::TwistWithCovarianceStamped twist_msg;
      twist_msg.header = out.header;
      twist_msg.twist = out.twist;
      twist_pub_.publish(twist_msg);
    }
    // tf needs a full pose: a position-only estimate (disparity) publishes none rather than a guess.
    if (out.orientation_valid) {
      const auto& p = out.pose.pose.position;
      const auto& q = out.pose.pose.orientation;
      geometry_msgs::TransformStamped t = tf2::eigenToTransform(Eigen::Isometry3d(
          Eigen::Translation3d(p.x, p.y, p.z) * Eigen::Quaterniond(q.w, q.x, q.y, q.z)));
      t.header = out.header;
      t.child_frame_id = docking_msgs::frames::kTarget;
      tf_broadcaster_.sendTransform(t);
    }
  }

  void diagnose(diagnostic_updater::DiagnosticStatusWrapper& stat) {
    const Decision& d = last_decision_;
    const double now = ros::Time::now().toSec();
    if (was_silent_) {
      stat.summary(diagnostic_msgs::DiagnosticStatus::ERROR, silenceText(now));
    } else if (d.code == DecisionCode::kChosen) {
      stat.summaryf(diagnostic_msgs::DiagnosticStatus::OK, "using %s", sourceName(d.source));
    } else if (d.code == DecisionCode::kChosenOverDisagreement) {
      stat.summaryf(diagnostic_msgs::DiagnosticStatus::WARN, "using %s; another source contradicted it",
                    sourceName(d.source));
    } else if (d.code == DecisionCode::kSourcesDisagree) {
      stat.summary(diagnostic_msgs::DiagnosticStatus::WARN, "sources disagree: nothing published as valid");
    } else {
      stat.summary(diagnostic_msgs::DiagnosticStatus::WARN, "no usable estimate");
    }
    stat.add("code", decisionCodeName(d.code));
    stat.add("reason", d.reason);
    stat.add("regime", regimeName(d.regime));
    stat.add("output frame", output_frame_);
    for (Source s : {Source::kDisparity, Source::kMonoVisible, Source::kMonoIr}) {
      const auto& latest = arbiter_.latest(s);
      stat.add(std::string(sourceName(s)) + " age (s)", latest ? std::to_string(now - latest->stamp_s) : "never");
    }
    stat.add("published", published_);
    docking_msgs::addLatency(stat, "image->target estimate", latency_);
    stat.add("rejected (out of order / bad stamp)", arbiter_.rejectedCount());
    stat.add("clock jumps back (ordering reset)", arbiter_.clockJumpsBack());
    for (const auto& [code, count] : rejections_by_code_) stat.add("dropped: " + code, count);
    if (!last_rejection_.empty()) stat.add("last dropped", last_rejection_);
    stat.add("tf failures", tf_failures_);
    const ConsistencyCounts& k = arbiter_.consistencyCounts();
    stat.add("consistency check", arbiter_.config().consistency.enabled ? "on" : "off");
    stat.add("consistency: pairs compared", k.comparisons);
    stat.add("consistency: disagreements", k.disagreements);
    stat.add("consistency: decided by a third source", k.resolved_by_third_source);
    stat.add("consistency: decided by the previous output", k.resolved_by_previous_output);
    stat.add("consistency: undecided", k.undecided);
    if (tf_failures_ > 0) stat.add("last tf error", last_tf_error_);
  }

  SourceArbiter arbiter_;
  std::string output_frame_;
  tf2_ros::Buffer tf_buffer_;
  tf2_ros::TransformListener tf_listener_;
  tf2_ros::TransformBroadcaster tf_broadcaster_;
  diagnostic_updater::Updater diagnostics_;
  std::unique_ptr<dynamic_reconfigure::Server<docking_perception::ArbiterConfig>> reconfigure_server_;
  ros::Publisher estimate_pub_, pose_pub_, twist_pub_, status_pub_;
  std::vector<ros::Subscriber> subscribers_;
  ros::Timer timer_;
  /// The latest valid estimate of each source, in output_frame_ (empty: invalid or no transform).
  std::array<std::optional<docking_msgs::TargetEstimate>, kSourceCount> latest_msgs_{};
  Decision last_decision_;
  std::unique_ptr<InputSilence> silence_;
  bool was_silent_{false};  // the last decision was "no estimator talks"
  std::uint64_t published_{0};
  docking_msgs::LatencyWindow latency_;  // image stamp -> the chosen estimate published
  std::uint64_t tf_failures_{0};
  std::string last_tf_error_;
  std::map<std::string, std::uint64_t> rejections_by_code_;  ///< dropped estimates by problem code
  std::string last_rejection_;                               ///< source, publisher, code and reason
};

}  // namespace
}  // namespace arbiter
}  // namespace docking_perception

int main(int argc, char** argv) {
  ros::init(argc, argv, "arbiter");
  return docking_settings::runNode([] {
    ros::NodeHandle nh;
    ros::NodeHandle pnh("~");
    docking_perception::arbiter::ArbiterNode node(nh, pnh, docking_perception::arbiter::loadSettings(pnh));
    ros::spin();
  });
}
