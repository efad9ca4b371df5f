// MonoPoseNodelet: the ROS shell around mono::MonoPoseEstimator. Loads its settings (declared in
// settings/mono_pose.yaml; config/mono_pose_<mode>.yaml holds what differs from the defaults), subscribes lazily to a rectified image + camera_info, publishes a
// TargetEstimate per image (valid = false with the reason when the target is not found), a debug image,
// diagnostics, and takes dynamic_reconfigure updates. No algorithm lives here.
#include <docking_settings/param_reader.h>
#include <docking_settings/reconfigure.h>
#include <docking_settings/ros_loader.h>
#include <cv_bridge/cv_bridge.h>
#include <diagnostic_updater/diagnostic_updater.h>
#include <dynamic_reconfigure/server.h>
#include <image_transport/image_transport.h>
#include <nodelet/nodelet.h>
#include <pluginlib/class_list_macros.hpp>
#include <ros/ros.h>
#include <sensor_msgs/image_encodings.h>

#include <Eigen/Geometry>
#include <atomic>
#include <cmath>
#include <boost/thread/recursive_mutex.hpp>
#include <fstream>
#include <map>
#include <memory>
#include <mutex>
#include <stdexcept>
#include <string>
#include <vector>

#include "docking_msgs/TargetEstimate.h"
#include "docking_msgs/estimate_check_msg.h"
#include "docking_msgs/latency_window.h"
#include "docking_msgs/names.h"
#include "docking_msgs/thread_cpu_time.h"
#include "docking_perception/MonoPoseConfig.h"
#include "docking_perception/duty/fused_range_condition.h"
#include "docking_perception/image_guard/rate_cap.h"
#include "docking_perception/mono/debug_drawing.h"
#include "docking_perception/mono/mono_pose_estimator.h"
#include "docking_perception/mono/mono_pose_settings.h"
#include "docking_perception/mono/stages.h"

namespace docking_perception {

// The message's REJECT_* constants mirror mono::RejectReason, in the same order.
static_assert(docking_msgs::TargetEstimate::REJECT_APPEARANCE == static_cast<int>(mono::RejectReason::kAppearance) &&
                  docking_msgs::TargetEstimate::REJECT_DOT_APPEARANCE == static_cast<int>(mono::RejectReason::kDotAppearance) &&
                  docking_msgs::TargetEstimate::REJECT_HINT_DISAGREEMENT ==
                      static_cast<int>(mono::RejectReason::kHintDisagreement) &&
                  docking_msgs::TargetEstimate::REJECT_POSITION_UNCERTAIN ==
                      static_cast<int>(mono::RejectReason::kPositionUncertain),
              "TargetEstimate REJECT_* and mono::RejectReason differ");
static_assert(docking_msgs::TargetEstimate::STAGE_PASSED == 0, "a stage's outcome 0 is 'passed' (mono/stages.h)");

class MonoPoseNodelet : public nodelet::Nodelet {
 public:
  ~MonoPoseNodelet() override = default;

 private:
  void onInit() override;
  // The settings (ConfigError naming the first bad one) and the target model they name.
  void loadSettings();
  void connectionChanged();
  void imageCallback(const sensor_msgs::ImageConstPtr& image, const sensor_msgs::CameraInfoConstPtr& info);
  void processImage(const sensor_msgs::ImageConstPtr& image, const sensor_msgs::CameraInfoConstPtr& info);
  void reconfigure(MonoPoseConfig& config, uint32_t level);
  void diagnose(diagnostic_updater::DiagnosticStatusWrapper& status);
  void publishEstimate(const std_msgs::Header& header, const mono::MonoPoseResult& result);
  docking_msgs::TargetEstimate toMessage(const std_msgs::Header& header, const mono::MonoPoseResult& result) const;
  // The stage of an image refused before the estimator (camera_info, encoding, an exception).
  static void refuseInput(mono::InputOutcome outcome, const std::string& status, mono::MonoPoseResult* result);
  // The estimator for camera_info's intrinsics (made, or told of new ones); false (refused) when unusable.
  bool readyFor(const sensor_msgs::CameraInfo& info, mono::MonoPoseResult* result);
  bool converted(const sensor_msgs::ImageConstPtr& image, cv_bridge::CvImageConstPtr* cv_image,
                 mono::MonoPoseResult* result);
  // Visible mode: the latest disparity estimate older than this image, as the estimator's position hint.
  void applyDisparityHint(const std_msgs::Header& image_header);
  void publishDebugImage(const std_msgs::Header& header, const cv::Mat& image, const mono::MonoPoseResult& result);
  // Visible mode: the disparity detector's estimate (same camera) as the region to search first.
  void disparityCallback(const docking_msgs::TargetEstimateConstPtr& estimate);
  // Far throttle (issue 15): the arbiter's output says whether the target is far and on disparity.
  void fusedCallback(const docking_msgs::TargetEstimateConstPtr& fused);
  // True when this image is left out: the target is far on disparity and the image comes sooner than
  // far_throttle_max_rate_hz allows.
  bool throttledFar(const ros::Time& stamp);

  ros::NodeHandle nh_;
  ros::NodeHandle private_nh_;
  std::unique_ptr<image_transport::ImageTransport> image_transport_;
  image_transport::CameraSubscriber camera_subscriber_;
  image_transport::Publisher debug_publisher_;
  ros::Publisher estimate_publisher_;
  ros::Subscriber disparity_subscriber_;
  ros::Subscriber fused_subscriber_;
  std::unique_ptr<diagnostic_updater::Updater> diagnostics_;
  ros::Timer diagnostics_timer_;
  boost::recursive_mutex reconfigure_mutex_;
  std::unique_ptr<dynamic_reconfigure::Server<MonoPoseConfig>> reconfigure_server_;

  // Subscription changes have their own lock: shutting a subscriber down waits for its running
  // callback, which may itself be waiting for mutex_.
  std::mutex connect_mutex_;
  std::atomic<bool> subscribed_{false};
  std::mutex mutex_;  // guards everything below (image, reconfigure and diagnostics callbacks)
  std::string image_topic_;
  uint8_t source_ = docking_msgs::TargetEstimate::SOURCE_MONO_VISIBLE;
  mono::MonoPoseNodeSettings settings_;
  std::unique_ptr<mono::TargetModel> model_;
  std::unique_ptr<mono::MonoPoseEstimator> estimator_;
  // For diagnostics.
  std::string last_status_ = "no image yet";
  bool last_valid_ = false;
  std::string camera_error_;
  int images_ = 0;
  int found_ = 0;
  double last_processing_ms_ = 0.0;
  int last_inliers_ = 0;
  // Debug images are drawn only while someone subscribes: what they cost, and proof of none without.
  unsigned long debug_images_ = 0;
  double debug_image_cpu_ms_total_ = 0.0;
  // The latest valid disparity estimate (visible mode), applied before the next image.
  docking_msgs::TargetEstimateConstPtr disparity_hint_;
  int hints_used_ = 0;
  // Image stamp -> this estimate's publication (diagnostics: this stage's share of the chain's latency).
  docking_msgs::LatencyWindow latency_;
  // Far throttle: beyond far_throttle_beyond_range_m on disparity, at most far_throttle_max_rate_hz.
  duty::FusedRangeCondition far_{duty::RangeSide::kBeyond};
  image_guard::RateCap far_rate_cap_;
  duty::FusedRangeState far_state_ = duty::FusedRangeState::kNoFusedEstimate;  // as last applied
  unsigned long images_throttled_far_ = 0;
  // Estimates published per deciding (stage, outcome) (mono/stages.h): the diagnostics' counts.
  std::map<std::pair<uint8_t, uint8_t>, unsigned long> decided_;
};

void MonoPoseNodelet::loadSettings() {
  docking_settings::loadSettings(private_nh_, settings_);
  docking_settings::warnUnknownKeys(private_nh_, settings_);
  docking_settings::ParamReader(private_nh_).validated([&] { mono::validate(settings_.core); });
  const mono::FarThrottleSettings& far = settings_.far_throttle;
  duty::FusedRangeConditionParams far_params;
  far_params.range_m = far.beyond_range_m;
  // Constants of the throttle: full rate again 0.1 m inside beyond_range_m (no chatter on a
  // range at the limit), and when no fused estimate came for 0.3 s (4-9 images at the cameras' 15-30 Hz).
  far_params.hysteresis_m = 0.1;
  far_params.max_fused_age_s = 0.3;
  far_.setParams(far_params);
  far_rate_cap_ = image_guard::RateCap(far.max_rate_hz);
  try {
    model_ = std::make_unique<mono::TargetModel>(
        mono::TargetModel::loadFromYaml(settings_.target_yaml, mono::modeOf(settings_.core) == mono::MonoMode::kVisible));
  } catch (const mono::TargetModelError& e) {
    docking_settings::ParamReader(private_nh_).invalid("target_yaml", e.what());
  }
}

void MonoPoseNodelet::onInit() {
  nh_ = getNodeHandle();
  private_nh_ = getPrivateNodeHandle();
  try {
    loadSettings();
  } catch (const docking_settings::ConfigError& e) {
    // Thrown, not ros::requestShutdown(): the nodelet loader catches it, refuses this nodelet and
    // says so (perception_host runs without it; a `nodelet load` process exits non-zero), while the
    // process keeps running. A shutdown requested from inside the loader's service call tore the
    // manager down with the loader's mutex still locked (boost::lock_error on the way out).
    // nodelet::Loader logs the exception's message at DEBUG only: said here first.
    NODELET_FATAL("mono_pose: %s (settings: src/docking_perception/settings/mono_pose.yaml)", e.what());
    throw std::runtime_error(std::string("mono_pose: ") + e.what());
  }
  const bool visible = mono::modeOf(settings_.core) == mono::MonoMode::kVisible;
  const std::string& mode_name = settings_.core.mode;
  source_ = visible ? docking_msgs::TargetEstimate::SOURCE_MONO_VISIBLE : docking_msgs::TargetEstimate::SOURCE_MONO_IR;
  image_topic_ = visible ? docking_msgs::topics::kStereoLeftImageRect : docking_msgs::topics::kIrImageRect;
  const std::string estimate_topic =
      visible ? docking_msgs::topics::kMonoVisibleEstimate : docking_msgs::topics::kMonoIrEstimate;
  // The debug image sits beside the estimate: perception/mono_<mode>/debug_image.
  const std::string debug_topic = ros::names::parentNamespace(estimate_topic) + "/debug_image";

  image_transport_ = std::make_unique<image_transport::ImageTransport>(nh_);
  diagnostics_ = std::make_unique<diagnostic_updater::Updater>(nh_, private_nh_, getName());
  diagnostics_->setHardwareID("mono_pose_" + mode_name);
  diagnostics_->add("mono_pose " + mode_name, this, &MonoPoseNodelet::diagnose);
  diagnostics_timer_ = nh_.createTimer(ros::Duration(1.0), [this](const ros::TimerEvent&) { diagnostics_->update(); });

  // Lazy: the camera is subscribed only while someone listens to the estimate or the debug image.
  {
    std::lock_guard<std::mutex> lock(connect_mutex_);
    estimate_publisher_ = nh_.advertise<docking_msgs::TargetEstimate>(
        estimate_topic, 5, [this](const ros::SingleSubscriberPublisher&) { connectionChanged(); },
        [this](const ros::SingleSubscriberPublisher&) { connectionChanged(); });
    debug_publisher_ = image_transport_->advertise(
        debug_topic, 1, [this](const image_transport::SingleSubscriberPublisher&) { connectionChanged(); },
        [this](const image_transport::SingleSubscriberPublisher&) { connectionChanged(); });
  }
  if (visible) {
    // Far from the target the whole-frame search spends its keypoints on the room; the stereo blob
    // says where to look (issue 11: cold starts over clutter).
    disparity_subscriber_ = nh_.subscribe(docking_msgs::topics::kDisparityEstimate, 1,
                                          &MonoPoseNodelet::disparityCallback, this, ros::TransportHints().tcpNoDelay());
  }
  // Far from the target the arbiter uses disparity: this stage then needs far fewer frames.
  fused_subscriber_ = nh_.subscribe(docking_msgs::topics::kTargetEstimate, 1, &MonoPoseNodelet::fusedCallback, this,
                                    ros::TransportHints().tcpNoDelay());  // small and timely: no Nagle delay
  reconfigure_server_ = std::make_unique<dynamic_reconfigure::Server<MonoPoseConfig>>(reconfigure_mutex_, private_nh_);
  reconfigure_server_->setCallback([this](MonoPoseConfig& config, uint32_t level) { reconfigure(config, level); });
  NODELET_INFO("mono_pose (%s, %s): %s -> %s, debug image on %s", mode_name.c_str(),
               settings_.core.solver.c_str(), nh_.resolveName(image_topic_).c_str(),
               nh_.resolveName(estimate_topic).c_str(), nh_.resolveName(debug_topic).c_str());
  connectionChanged();
}

void MonoPoseNodelet::connectionChanged() {
  std::lock_guard<std::mutex> lock(connect_mutex_);
  if (!image_transport_) return;
  const bool wanted = estimate_publisher_.getNumSubscribers() > 0 || debug_publisher_.getNumSubscribers() > 0;
  if (wanted && !camera_subscriber_) {
    camera_subscriber_ = image_transport_->subscribeCamera(image_topic_, 2, &MonoPoseNodelet::imageCallback, this);
  } else if (!wanted && camera_subscriber_) {
    camera_subscriber_.shutdown();
  }
  subscribed_ = static_cast<bool>(camera_subscriber_);
}

void MonoPoseNodelet::reconfigure(MonoPoseConfig& config, uint32_t /*level*/) {
  std::lock_guard<std::mutex> lock(mutex_);
  dynamic_reconfigure::Config message;
  config.__toMessage__(message);
  mono::MonoPoseNodeSettings next = settings_;
  docking_settings::applyReconfigure(message, next);
  try {
    mono::validate(next.core);
    if (estimator_) estimator_->setParams(next.core);
    settings_ = next;
  } catch (const std::exception& e) {
    NODELET_ERROR("mono_pose: reconfigure rejected: %s; keeping the previous values", e.what());
    // Show the values in force, not the refused ones (the server publishes what the callback leaves).
    dynamic_reconfigure::Config kept = docking_settings::toReconfigure(settings_);
    config.__fromMessage__(kept);
  }
}

void MonoPoseNodelet::disparityCallback(const docking_msgs::TargetEstimateConstPtr& estimate) {
  if (!estimate->valid || !estimate->position_valid) return;
  const auto& p = estimate->pose.pose.position;
  if (!std::isfinite(p.x) || !std::isfinite(p.y) || !std::isfinite(p.z)) return;
  std::lock_guard<std::mutex> lock(mutex_);
  disparity_hint_ = estimate;
}

void MonoPoseNodelet::fusedCallback(const docking_msgs::TargetEstimateConstPtr& fused) {
  std::lock_guard<std::mutex> lock(mutex_);
  far_.onFusedEstimate(ros::Time::now().toSec(), fused->valid && fused->position_valid,
                       fused->selected_source == docking_msgs::TargetEstimate::SOURCE_DISPARITY, fused->range_m);
}

bool MonoPoseNodelet::throttledFar(const ros::Time& stamp) {
  std::lock_guard<std::mutex> lock(mutex_);
  far_state_ = far_.state(ros::Time::now().toSec());
  if (far_state_ != duty::FusedRangeState::kHolds || far_rate_cap_.admit(stamp.toSec())) return false;
  ++images_throttled_far_;
  return true;
}

// Nothing an image contains may end the manager: whatever the estimator throws (cv::Exception is a
// std::exception) drops that image with an invalid estimate saying why, and the next one is processed.
void MonoPoseNodelet::imageCallback(const sensor_msgs::ImageConstPtr& image,
                                    const sensor_msgs::CameraInfoConstPtr& info) {
  try {
    if (throttledFar(image->header.stamp)) return;
    processImage(image, info);
  } catch (const std::exception& e) {
    NODELET_ERROR_THROTTLE(5.0, "mono_pose: image dropped: %s", e.what());
    try {
      std::lock_guard<std::mutex> lock(mutex_);
      mono::MonoPoseResult result;
      result.solver = settings_.core.solver;
      refuseInput(mono::InputOutcome::kDropped, std::string("image dropped: ") + e.what(), &result);
      publishEstimate(image->header, result);
    } catch (const std::exception& again) {
      NODELET_ERROR_THROTTLE(5.0, "mono_pose: could not report the dropped image: %s", again.what());
    }
  }
}

void MonoPoseNodelet::processImage(const sensor_msgs::ImageConstPtr& image,
                                   const sensor_msgs::CameraInfoConstPtr& info) {
  std::lock_guard<std::mutex> lock(mutex_);
  mono::MonoPoseResult result;
  result.solver = settings_.core.solver;
  cv_bridge::CvImageConstPtr cv_image;
  if (!readyFor(*info, &result) || !converted(image, &cv_image, &result)) {
    publishEstimate(image->header, result);
    return;
  }
  applyDisparityHint(image->header);
  // Time comes from the image: live, simulated and replayed alike.
  result = estimator_->process(cv_image->image, image->header.stamp.toSec());
  ++images_;
  found_ += result.valid ? 1 : 0;
  last_valid_ = result.valid;
  last_status_ = result.valid ? "found" : result.status;
  last_processing_ms_ = result.processing_time_ms;
  last_inliers_ = result.feature_inliers;
  publishEstimate(image->header, result);
  if (settings_.publish_debug_image && debug_publisher_.getNumSubscribers() > 0) {
    publishDebugImage(image->header, cv_image->image, result);
  }
}

void MonoPoseNodelet::refuseInput(mono::InputOutcome outcome, const std::string& status, mono::MonoPoseResult* result) {
  result->status = status;
  result->reject_reason = mono::RejectReason::kBadInput;
  result->stage = mono::Stage::kInput;
  result->stage_outcome = static_cast<uint8_t>(outcome);
}

bool MonoPoseNodelet::readyFor(const sensor_msgs::CameraInfo& info, mono::MonoPoseResult* result) {
  // Intrinsics of the rectified image: the projection matrix P.
  mono::CameraIntrinsics camera;
  camera.fx = info.P[0];
  camera.cx = info.P[2];
  camera.fy = info.P[5];
  camera.cy = info.P[6];
  camera.width = static_cast<int>(info.width);
  camera.height = static_cast<int>(info.height);
  std::string reason;
  if (!camera.isValid(&reason)) {
    camera_error_ = "camera_info on " + image_topic_ + ": " + reason;
    refuseInput(mono::InputOutcome::kBadCameraInfo, camera_error_, result);
    NODELET_WARN_THROTTLE(5.0, "mono_pose: %s", camera_error_.c_str());
    return false;
  }
  camera_error_.clear();
  try {
    if (!estimator_) {
      estimator_ = std::make_unique<mono::MonoPoseEstimator>(*model_, camera, settings_.core);
    } else if (camera.fx != estimator_->camera().fx || camera.fy != estimator_->camera().fy ||
               camera.cx != estimator_->camera().cx || camera.cy != estimator_->camera().cy ||
               camera.width != estimator_->camera().width || camera.height != estimator_->camera().height) {
      estimator_->setCamera(camera);
      estimator_->reset();
    }
  } catch (const std::exception& e) {
    camera_error_ = e.what();
    refuseInput(mono::InputOutcome::kBadCameraInfo, camera_error_, result);
    NODELET_ERROR_THROTTLE(5.0, "mono_pose: %s", e.what());
    return false;
  }
  return true;
}

bool MonoPoseNodelet::converted(const sensor_msgs::ImageConstPtr& image, cv_bridge::CvImageConstPtr* cv_image,
                                mono::MonoPoseResult* result) {
  try {
    const bool mono8 = image->encoding == sensor_msgs::image_encodings::MONO8;
    *cv_image = cv_bridge::toCvShare(image, mono8 ? sensor_msgs::image_encodings::MONO8
                                                  : sensor_msgs::image_encodings::BGR8);
  } catch (const cv_bridge::Exception& e) {
    refuseInput(mono::InputOutcome::kNotConvertible, std::string("cannot convert the image: ") + e.what(), result);
    return false;
  }
  return true;
}

void MonoPoseNodelet::applyDisparityHint(const std_msgs::Header& image_header) {
  // Only a hint older than this image: the disparity of this very frame races with it, and which one
  // won would make the result depend on thread timing (a lossless replay would not repeat itself). A
  // same-frame hint waits for the next image (live, the disparity is the slower one anyway).
  if (!disparity_hint_ || !(disparity_hint_->header.stamp < image_header.stamp)) return;
  if (disparity_hint_->header.frame_id == image_header.frame_id) {
    const auto& position = disparity_hint_->pose.pose.position;
    estimator_->setPositionHint(Eigen::Vector3d(position.x, position.y, position.z),
                                disparity_hint_->header.stamp.toSec());
    ++hints_used_;
  } else {
    NODELET_WARN_THROTTLE(10.0, "mono_pose: disparity estimate in frame '%s', image in '%s': not used as a search hint",
                          disparity_hint_->header.frame_id.c_str(), image_header.frame_id.c_str());
  }
  disparity_hint_.reset();
}

void MonoPoseNodelet::publishDebugImage(const std_msgs::Header& header, const cv::Mat& image,
                                        const mono::MonoPoseResult& result) {
  const double cpu_start_ms = docking_msgs::threadCpuMs();
  cv_bridge::CvImage debug(header, sensor_msgs::image_encodings::BGR8,
                           mono::drawDebugImage(image, result, estimator_->camera(), *model_));
  debug_publisher_.publish(debug.toImageMsg());
  ++debug_images_;
  debug_image_cpu_ms_total_ += docking_msgs::threadCpuMs() - cpu_start_ms;
}
void MonoPoseNodelet::publishEstimate(const std_msgs::Header& header, const mono::MonoPoseResult& result) {
  docking_msgs::TargetEstimate msg = toMessage(header, result);
  // What the arbiter would refuse (a NaN, a non-unit quaternion) leaves here as not valid, with the code.
  const auto problem = docking_msgs::checks::withdrawIfMalformed(&msg);
  if (problem != docking_msgs::checks::EstimateProblem::kNone) {
    NODELET_ERROR_THROTTLE(5.0, "mono_pose: estimate withdrawn: %s", docking_msgs::checks::estimateProblemName(problem));
    msg.stage = static_cast<uint8_t>(mono::Stage::kSolve);  // as its reject_reason says: an implausible pose
    msg.stage_outcome = static_cast<uint8_t>(mono::SolveOutcome::kImplausible);
  }
  ++decided_[{msg.stage, msg.stage_outcome}];
  estimate_publisher_.publish(msg);
  if (!header.stamp.isZero()) latency_.add((ros::Time::now() - header.stamp).toSec());
}

docking_msgs::TargetEstimate MonoPoseNodelet::toMessage(const std_msgs::Header& header,
                                                        const mono::MonoPoseResult& result) const {
  docking_msgs::TargetEstimate msg;
  msg.header = header;
  msg.source = source_;
  msg.selected_source = source_;
  msg.valid = result.valid;
  msg.position_valid = result.valid;
  msg.orientation_valid = result.valid && result.orientation_valid;
  msg.twist_valid = result.valid && result.twist.valid;
  const Eigen::Quaterniond q(result.pose.rotation);
  msg.pose.pose.position.x = result.pose.translation.x();
  msg.pose.pose.position.y = result.pose.translation.y();
  msg.pose.pose.position.z = result.pose.translation.z();
  msg.pose.pose.orientation.x = q.x();
  msg.pose.pose.orientation.y = q.y();
  msg.pose.pose.orientation.z = q.z();
  msg.pose.pose.orientation.w = q.w();
  msg.twist.twist.linear.x = result.twist.linear.x();
  msg.twist.twist.linear.y = result.twist.linear.y();
  msg.twist.twist.linear.z = result.twist.linear.z();
  msg.twist.twist.angular.x = result.twist.angular.x();
  msg.twist.twist.angular.y = result.twist.angular.y();
  msg.twist.twist.angular.z = result.twist.angular.z();
  // Row-major 6x6; components that are not valid carry 1e6 (the message's convention).
  const mono::Matrix6d unknown = mono::Matrix6d::Identity() * 1e6;
  const mono::Matrix6d& pose_covariance = result.valid ? result.pose.covariance : unknown;
  const mono::Matrix6d& twist_covariance = msg.twist_valid ? result.twist.covariance : unknown;
  for (int r = 0; r < 6; ++r) {
    for (int c = 0; c < 6; ++c) {
      msg.pose.covariance[static_cast<size_t>(6 * r + c)] = pose_covariance(r, c);
      msg.twist.covariance[static_cast<size_t>(6 * r + c)] = twist_covariance(r, c);
    }
  }
  msg.range_m = result.range_m;
  msg.feature_matches = static_cast<uint32_t>(std::max(0, result.feature_matches));
  msg.feature_inliers = static_cast<uint32_t>(std::max(0, result.feature_inliers));
  msg.reprojection_error_px = result.reprojection_error_px;
  msg.disparity_px = 0.0;
  msg.processing_time_ms = result.processing_time_ms;
  msg.solver = result.solver;
  msg.status = result.status;  // a valid result's status says what part is withheld, if any
  msg.reject_reason = static_cast<uint8_t>(result.valid ? mono::RejectReason::kNone : result.reject_reason);
  msg.stage = static_cast<uint8_t>(result.stage);  // the stage that decided and its code (mono/stages.h)
  msg.stage_outcome = result.stage_outcome;
  return msg;
}
void MonoPoseNodelet::diagnose(diagnostic_updater::DiagnosticStatusWrapper& status) {
  std::lock_guard<std::mutex> lock(mutex_);
  if (!camera_error_.empty()) {
    status.summary(diagnostic_msgs::DiagnosticStatus::ERROR, camera_error_);
  } else if (!subscribed_) {
    status.summary(diagnostic_msgs::DiagnosticStatus::OK, "idle: nobody subscribes to the estimate");
  } else if (images_ == 0) {
    status.summary(diagnostic_msgs::DiagnosticStatus::WARN, "no image received on " + image_topic_);
  } else if (!last_valid_) {
    status.summary(diagnostic_msgs::DiagnosticStatus::WARN, "target not found: " + last_status_);
  } else {
    status.summary(diagnostic_msgs::DiagnosticStatus::OK, "target found");
  }
  status.add("mode", settings_.core.mode);
  status.add("solver", settings_.core.solver);
  status.add("images", images_);
  status.add("found", found_);
  status.add("last status", last_status_);
  status.add("last processing time ms", last_processing_ms_);
  status.add("last inliers", last_inliers_);
  status.add("disparity search hints used", hints_used_);
  status.add("far throttle (target far on disparity)", duty::describe(far_state_));
  status.add("images left out far", images_throttled_far_);
  status.add("debug images drawn", debug_images_);
  status.add("debug image CPU ms (mean)", debug_images_ > 0 ? debug_image_cpu_ms_total_ / debug_images_ : 0.0);
  for (const auto& [decision, count] : decided_) {
    const auto stage = static_cast<mono::Stage>(decision.first);
    status.add(std::string("decided at ") + mono::stageName(stage) + ": " + mono::outcomeName(stage, decision.second),
               count);
  }
  docking_msgs::addLatency(status, "image->estimate", latency_);
}

}  // namespace docking_perception

PLUGINLIB_EXPORT_CLASS(docking_perception::MonoPoseNodelet, nodelet::Nodelet)
