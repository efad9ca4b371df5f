// MonoPoseNodelet: the ROS shell around mono::MonoPoseEstimator. Reads and validates its parameters
// (config/mono_pose_<mode>.yaml), subscribes lazily to a rectified image + camera_info, publishes a
// TargetEstimate per image (valid = false with the reason when the target is not found), a debug image,
// diagnostics, and takes dynamic_reconfigure updates. No algorithm lives here.
#include <docking_settings/param_reader.h>
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
#include "docking_perception/mono/mono_pose_param_keys.h"

namespace docking_perception {

class MonoPoseNodelet : public nodelet::Nodelet {
 public:
  ~MonoPoseNodelet() override = default;

 private:
  void onInit() override;
  bool readParameters(std::vector<std::string>* errors);
  template <typename T>
  void require(const std::string& name, T* value, std::vector<std::string>* errors);
  void connectionChanged();
  void imageCallback(const sensor_msgs::ImageConstPtr& image, const sensor_msgs::CameraInfoConstPtr& info);
  void processImage(const sensor_msgs::ImageConstPtr& image, const sensor_msgs::CameraInfoConstPtr& info);
  void reconfigure(MonoPoseConfig& config, uint32_t level);
  void diagnose(diagnostic_updater::DiagnosticStatusWrapper& status);
  void publishEstimate(const std_msgs::Header& header, const mono::MonoPoseResult& result);
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
  std::string mode_name_;
  std::string image_topic_;
  uint8_t source_ = docking_msgs::TargetEstimate::SOURCE_MONO_VISIBLE;
  mono::MonoPoseParams params_;
  std::unique_ptr<mono::TargetModel> model_;
  std::unique_ptr<mono::MonoPoseEstimator> estimator_;
  bool publish_debug_image_ = true;
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
};

template <typename T>
void MonoPoseNodelet::require(const std::string& name, T* value, std::vector<std::string>* errors) {
  try {
    *value = docking_settings::ParamReader(private_nh_).require<T>(name);
  } catch (const docking_settings::ConfigError& e) {
    errors->push_back(e.what());
  }
}

bool MonoPoseNodelet::readParameters(std::vector<std::string>* errors) {
  std::string target_yaml;
  std::string solver;
  std::string velocity;
  require("mode", &mode_name_, errors);
  require("target_yaml", &target_yaml, errors);
  require("solver", &solver, errors);
  require("velocity_method", &velocity, errors);
  mono::MonoPoseParams& p = params_;
  mono::visitMonoPoseParams(p, [&](const char* key, auto* field) { require(key, field, errors); });
  require("publish_debug_image", &publish_debug_image_, errors);
  mono::FarThrottleSettings far;
  mono::visitFarThrottleSettings(far, [&](const char* key, double* field) { require(key, field, errors); });
  if (!errors->empty()) return false;
  const std::string far_problem = mono::validateFarThrottle(far);
  if (!far_problem.empty()) errors->push_back("parameter " + private_nh_.getNamespace() + "/" + far_problem);
  far_.setParams(far.far);
  far_rate_cap_ = image_guard::RateCap(far.max_rate_hz);

  mono::MonoMode mode;
  if (!mono::parseMonoMode(mode_name_, &mode)) {
    errors->push_back("parameter 'mode' must be 'visible' or 'ir', got '" + mode_name_ + "'");
  }
  if (!mono::parsePoseSolver(solver, &p.solver)) {
    errors->push_back("parameter 'solver' must be 'paper_5point' or 'pnp', got '" + solver + "'");
  }
  if (!mono::parseVelocityMethod(velocity, &p.velocity)) {
    errors->push_back("parameter 'velocity_method' must be 'kalman' or 'frame_difference', got '" + velocity + "'");
  }
  if (!errors->empty()) return false;
  p.mode = mode;
  p.pnp.min_pixel_sigma = p.min_pixel_sigma;
  const std::string invalid = mono::validateParams(p);
  if (!invalid.empty()) errors->push_back("parameter " + invalid);
  try {
    model_ = std::make_unique<mono::TargetModel>(
        mono::TargetModel::loadFromYaml(target_yaml, mode == mono::MonoMode::kVisible));
  } catch (const mono::TargetModelError& e) {
    errors->push_back(std::string("parameter 'target_yaml': ") + e.what());
  }
  return errors->empty();
}

void MonoPoseNodelet::onInit() {
  nh_ = getNodeHandle();
  private_nh_ = getPrivateNodeHandle();
  std::vector<std::string> errors;
  if (!readParameters(&errors)) {
    for (const std::string& error : errors) NODELET_FATAL("mono_pose: %s", error.c_str());
    // Thrown, not ros::requestShutdown(): the nodelet loader catches it, refuses this nodelet and
    // says so (perception_host runs without it; a `nodelet load` process exits non-zero), while the
    // process keeps running. A shutdown
    // requested from inside the loader's service call tore the manager down with the loader's mutex
    // still locked (boost::lock_error on the way out).
    // nodelet::Loader logs the exception's message at DEBUG only: said here first.
    const std::string message =
        "mono_pose: invalid or missing parameters (see above; all are listed in config/mono_pose_<mode>.yaml)";
    NODELET_FATAL("%s", message.c_str());
    throw std::runtime_error(message);
  }
  const bool visible = params_.mode == mono::MonoMode::kVisible;
  source_ = visible ? docking_msgs::TargetEstimate::SOURCE_MONO_VISIBLE : docking_msgs::TargetEstimate::SOURCE_MONO_IR;
  image_topic_ = visible ? docking_msgs::topics::kStereoLeftImageRect : docking_msgs::topics::kIrImageRect;
  const std::string estimate_topic =
      visible ? docking_msgs::topics::kMonoVisibleEstimate : docking_msgs::topics::kMonoIrEstimate;
  // The debug image sits beside the estimate: perception/mono_<mode>/debug_image.
  const std::string debug_topic = ros::names::parentNamespace(estimate_topic) + "/debug_image";

  image_transport_ = std::make_unique<image_transport::ImageTransport>(nh_);
  diagnostics_ = std::make_unique<diagnostic_updater::Updater>(nh_, private_nh_, getName());
  diagnostics_->setHardwareID("mono_pose_" + mode_name_);
  diagnostics_->add("mono_pose " + mode_name_, this, &MonoPoseNodelet::diagnose);
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
  NODELET_INFO("mono_pose (%s, %s): %s -> %s, debug image on %s", mode_name_.c_str(),
               mono::toString(params_.solver).c_str(), nh_.resolveName(image_topic_).c_str(),
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
  mono::MonoPoseParams next = params_;
  if (!mono::parsePoseSolver(config.solver, &next.solver) ||
      !mono::parseVelocityMethod(config.velocity_method, &next.velocity)) {
    NODELET_ERROR("mono_pose: reconfigure: unknown solver '%s' or velocity_method '%s'; keeping the old ones",
                  config.solver.c_str(), config.velocity_method.c_str());
    config.solver = mono::toString(params_.solver);
    config.velocity_method = mono::toString(params_.velocity);
    return;
  }
  next.use_tracking_region = config.use_tracking_region;
  next.tracking_margin_px = config.tracking_margin_px;
  next.max_reprojection_px = config.max_reprojection_px;
  next.min_pixel_sigma = config.min_pixel_sigma;
  next.pnp.min_pixel_sigma = config.min_pixel_sigma;
  next.features.ratio = config.feature_ratio;
  next.features.fast_threshold = config.fast_threshold;
  next.features.min_inliers = config.min_inliers;
  next.features.ransac_threshold_px = config.ransac_threshold_px;
  next.features.refine = config.refine_matches;
  next.use_direct_alignment = config.use_direct_alignment;
  next.direct.min_correlation = config.direct_min_correlation;
  next.leds.threshold = config.led_threshold;
  next.filter.accel_noise = config.accel_noise;
  next.filter.angular_accel_noise = config.angular_accel_noise;
  next.publish_filtered_orientation = config.publish_filtered_orientation;
  next.filtered_orientation_correlated_fraction = config.filtered_orientation_correlated_fraction;
  const std::string invalid = mono::validateParams(next);
  if (!invalid.empty()) {
    NODELET_ERROR("mono_pose: reconfigure rejected: %s", invalid.c_str());
    return;
  }
  try {
    if (estimator_) estimator_->setParams(next);
    params_ = next;
    publish_debug_image_ = config.publish_debug_image;
  } catch (const std::exception& e) {
    NODELET_ERROR("mono_pose: reconfigure rejected: %s", e.what());
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
      result.solver = mono::toString(params_.solver);
      result.status = std::string("image dropped: ") + e.what();
      result.reject_reason = mono::RejectReason::kBadInput;
      publishEstimate(image->header, result);
    } catch (const std::exception& again) {
      NODELET_ERROR_THROTTLE(5.0, "mono_pose: could not report the dropped image: %s", again.what());
    }
  }
}

void MonoPoseNodelet::processImage(const sensor_msgs::ImageConstPtr& image,
                                   const sensor_msgs::CameraInfoConstPtr& info) {
  std::lock_guard<std::mutex> lock(mutex_);
  // Intrinsics of the rectified image: the projection matrix P.
  mono::CameraIntrinsics camera;
  camera.fx = info->P[0];
  camera.cx = info->P[2];
  camera.fy = info->P[5];
  camera.cy = info->P[6];
  camera.width = static_cast<int>(info->width);
  camera.height = static_cast<int>(info->height);
  mono::MonoPoseResult result;
  result.solver = mono::toString(params_.solver);
  std::string reason;
  if (!camera.isValid(&reason)) {
    camera_error_ = "camera_info on " + image_topic_ + ": " + reason;
    result.status = camera_error_;
    result.reject_reason = mono::RejectReason::kBadInput;
    NODELET_WARN_THROTTLE(5.0, "mono_pose: %s", camera_error_.c_str());
    publishEstimate(image->header, result);
    return;
  }
  camera_error_.clear();
  try {
    if (!estimator_) {
      estimator_ = std::make_unique<mono::MonoPoseEstimator>(*model_, camera, params_);
    } else if (camera.fx != estimator_->camera().fx || camera.fy != estimator_->camera().fy ||
               camera.cx != estimator_->camera().cx || camera.cy != estimator_->camera().cy ||
               camera.width != estimator_->camera().width || camera.height != estimator_->camera().height) {
      estimator_->setCamera(camera);
      estimator_->reset();
    }
  } catch (const std::exception& e) {
    camera_error_ = e.what();
    result.status = camera_error_;
    result.reject_reason = mono::RejectReason::kBadInput;
    NODELET_ERROR_THROTTLE(5.0, "mono_pose: %s", e.what());
    publishEstimate(image->header, result);
    return;
  }

  cv_bridge::CvImageConstPtr cv_image;
  try {
    const std::string& encoding = image->encoding;
    const bool mono8 = encoding == sensor_msgs::image_encodings::MONO8;
    cv_image = cv_bridge::toCvShare(image, mono8 ? sensor_msgs::image_encodings::MONO8
                                                 : sensor_msgs::image_encodings::BGR8);
  } catch (const cv_bridge::Exception& e) {
    result.status = std::string("cannot convert the image: ") + e.what();
    result.reject_reason = mono::RejectReason::kBadInput;
    publishEstimate(image->header, result);
    return;
  }
  // Only a hint older than this image: the disparity of this very frame races with it, and which one
  // won would make the result depend on thread timing (a lossless replay would not repeat itself). A
  // same-frame hint waits for the next image (live, the disparity is the slower one anyway).
  if (disparity_hint_ && disparity_hint_->header.stamp < image->header.stamp) {
    if (disparity_hint_->header.frame_id == image->header.frame_id) {
      const auto& position = disparity_hint_->pose.pose.position;
      estimator_->setPositionHint(Eigen::Vector3d(position.x, position.y, position.z),
                                  disparity_hint_->header.stamp.toSec());
      ++hints_used_;
    } else {
      NODELET_WARN_THROTTLE(10.0, "mono_pose: disparity estimate in frame '%s', image in '%s': not used as a search hint",
                            disparity_hint_->header.frame_id.c_str(), image->header.frame_id.c_str());
    }
    disparity_hint_.reset();
  }
  // Time comes from the image: live, simulated and replayed alike.
  result = estimator_->process(cv_image->image, image->header.stamp.toSec());
  ++images_;
  found_ += result.valid ? 1 : 0;
  last_valid_ = result.valid;
  last_status_ = result.valid ? "found" : result.status;
  last_processing_ms_ = result.processing_time_ms;
  last_inliers_ = result.feature_inliers;
  publishEstimate(image->header, result);

  if (publish_debug_image_ && debug_publisher_.getNumSubscribers() > 0) {
    const double cpu_start_ms = docking_msgs::threadCpuMs();
    cv_bridge::CvImage debug(image->header, sensor_msgs::image_encodings::BGR8,
                             mono::drawDebugImage(cv_image->image, result, estimator_->camera(), *model_));
    debug_publisher_.publish(debug.toImageMsg());
    ++debug_images_;
    debug_image_cpu_ms_total_ += docking_msgs::threadCpuMs() - cpu_start_ms;
  }
}

void MonoPoseNodelet::publishEstimate(const std_msgs::Header& header, const mono::MonoPoseResult& result) {
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
  // The message's REJECT_* constants mirror mono::RejectReason, in the same order.
  static_assert(docking_msgs::TargetEstimate::REJECT_APPEARANCE == static_cast<int>(mono::RejectReason::kAppearance) &&
                    docking_msgs::TargetEstimate::REJECT_DOT_APPEARANCE ==
                        static_cast<int>(mono::RejectReason::kDotAppearance) &&
                    docking_msgs::TargetEstimate::REJECT_HINT_DISAGREEMENT ==
                        static_cast<int>(mono::RejectReason::kHintDisagreement) &&
                    docking_msgs::TargetEstimate::REJECT_POSITION_UNCERTAIN ==
                        static_cast<int>(mono::RejectReason::kPositionUncertain),
                "TargetEstimate REJECT_* and mono::RejectReason differ");
  msg.reject_reason = static_cast<uint8_t>(result.valid ? mono::RejectReason::kNone : result.reject_reason);
  // What the arbiter would refuse (a NaN, a non-unit quaternion) leaves here as not valid, with the code.
  const auto problem = docking_msgs::checks::withdrawIfMalformed(&msg);
  if (problem != docking_msgs::checks::EstimateProblem::kNone) {
    NODELET_ERROR_THROTTLE(5.0, "mono_pose: estimate withdrawn: %s", docking_msgs::checks::estimateProblemName(problem));
  }
  estimate_publisher_.publish(msg);
  if (!header.stamp.isZero()) latency_.add((ros::Time::now() - header.stamp).toSec());
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
  status.add("mode", mode_name_);
  status.add("solver", mono::toString(params_.solver));
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
  docking_msgs::addLatency(status, "image->estimate", latency_);
}

}  // namespace docking_perception

PLUGINLIB_EXPORT_CLASS(docking_perception::MonoPoseNodelet, nodelet::Nodelet)
