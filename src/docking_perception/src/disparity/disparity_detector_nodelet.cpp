#include "docking_perception/disparity/disparity_detector_nodelet.h"

#include <algorithm>
#include <cmath>
#include <sstream>
#include <stdexcept>
#include <vector>

#include <cv_bridge/cv_bridge.h>
#include <docking_msgs/estimate_check_msg.h>
#include <docking_msgs/names.h>
#include <docking_msgs/thread_cpu_time.h>
#include <image_geometry/pinhole_camera_model.h>
#include <image_transport/camera_common.h>
#include <pluginlib/class_list_macros.hpp>
#include <sensor_msgs/image_encodings.h>

#include "docking_perception/mono/target_model.h"
#include "docking_settings/param_reader.h"
#include "docking_settings/reconfigure.h"
#include "docking_settings/ros_loader.h"

namespace docking_perception {
namespace {

using docking_msgs::threadCpuMs;

// A camera_info of a window of the image (far_stereo_rectify's tracking window: image_geometry's region
// of interest, the principal point shifted by its offset).
bool isWindow(const sensor_msgs::CameraInfo& info) {
  return info.roi.width != 0 && info.roi.height != 0 &&
         (info.roi.width != info.width || info.roi.height != info.height);
}

// The window camera_info published with the pair a disparity image came from: the same stamp and size.
sensor_msgs::CameraInfoConstPtr windowInfoOf(const std::deque<sensor_msgs::CameraInfoConstPtr>& infos,
                                             const ros::Time& stamp, std::uint32_t width, std::uint32_t height) {
  for (auto it = infos.rbegin(); it != infos.rend(); ++it) {
    if ((*it)->header.stamp == stamp && (*it)->roi.width == width && (*it)->roi.height == height) return *it;
  }
  return nullptr;
}

// The message's reject code of the stage that decided: what a consumer may act on without reading the status.
std::uint8_t rejectReasonOf(bool found, disparity::StageOutcome outcome) {
  using Estimate = docking_msgs::TargetEstimate;
  if (found) return Estimate::REJECT_NONE;
  switch (outcome.stage) {
    case disparity::Stage::kInput: return Estimate::REJECT_BAD_INPUT;
    case disparity::Stage::kAppearance: return Estimate::REJECT_APPEARANCE;
    default: return Estimate::REJECT_NOT_FOUND;  // no blob, or none the mockup's size, shape or track
  }
}

// Stage 1 on the message: checked before its data is touched (a bad one is reported, never dereferenced).
disparity::StageOutcome checkMessage(const stereo_msgs::DisparityImage& message, std::string* problem) {
  namespace enc = sensor_msgs::image_encodings;
  using disparity::InputOutcome;
  const sensor_msgs::Image& image = message.image;
  std::ostringstream why;
  InputOutcome outcome = InputOutcome::kPassed;
  if (image.encoding != enc::TYPE_32FC1) {
    why << "disparity image encoding must be '" << enc::TYPE_32FC1 << "', got '" << image.encoding << "'";
    outcome = InputOutcome::kBadEncoding;
  } else if (image.width == 0 || image.height == 0) {
    why << "empty disparity image (" << image.width << "x" << image.height << ")";
    outcome = InputOutcome::kEmptyImage;
  } else if (image.step < image.width * sizeof(float) ||
             image.data.size() < static_cast<std::size_t>(image.step) * image.height) {
    why << "disparity image data (" << image.data.size() << " bytes, step " << image.step << ") too short for "
        << image.width << "x" << image.height << " floats";
    outcome = InputOutcome::kTruncatedData;
  } else if ((image.is_bigendian != 0) != (__BYTE_ORDER__ == __ORDER_BIG_ENDIAN__)) {
    why << "disparity image byte order (is_bigendian " << static_cast<int>(image.is_bigendian)
        << ") differs from this machine's";
    outcome = InputOutcome::kWrongByteOrder;
  } else if (!(message.f > 0.0) || !(message.T > 0.0)) {
    why << "DisparityImage focal length f (" << message.f << ") and baseline T (" << message.T << ") must be > 0";
    outcome = InputOutcome::kBadGeometry;
  }
  *problem = why.str();
  return outcome;
}

// The region the matcher can give disparities in: right of its blind left band (its largest disparity plus
// half its correlation window), inside its own valid window if it set one.
cv::Rect validRegionOf(const stereo_msgs::DisparityImage& message, int blind_band_extra_px) {
  const int blind_columns = std::max(0, static_cast<int>(std::ceil(message.max_disparity)) + blind_band_extra_px);
  cv::Rect valid_region(blind_columns, 0, static_cast<int>(message.image.width) - blind_columns,
                        static_cast<int>(message.image.height));
  if (message.valid_window.width > 0 && message.valid_window.height > 0) {
    valid_region &= cv::Rect(static_cast<int>(message.valid_window.x_offset),
                             static_cast<int>(message.valid_window.y_offset),
                             static_cast<int>(message.valid_window.width),
                             static_cast<int>(message.valid_window.height));
  }
  return valid_region;
}

// Disparity shown white in the debug image (0.86 m for our pair; nearer is the arbiter's monocular range).
constexpr double kDebugDisplayMaxDisparityPx = 64.0;

// Variance of the components a disparity estimate does not measure (TargetEstimate.msg: >= 1e6).
constexpr double kUnknownVariance = 1e6;

// The estimate every frame starts from: not valid, orientation and twist unknown.
docking_msgs::TargetEstimate blankEstimate(const std_msgs::Header& header) {
  docking_msgs::TargetEstimate estimate;
  estimate.header = header;
  if (estimate.header.frame_id.empty()) {
    estimate.header.frame_id = docking_msgs::frames::kStereoLeftOptical;
  }
  estimate.source = docking_msgs::TargetEstimate::SOURCE_DISPARITY;
  estimate.selected_source = docking_msgs::TargetEstimate::SOURCE_DISPARITY;
  estimate.valid = false;
  estimate.position_valid = false;
  estimate.orientation_valid = false;
  estimate.twist_valid = false;
  estimate.pose.pose.orientation.w = 1.0;
  for (int i = 0; i < 6; ++i) {
    estimate.pose.covariance[static_cast<std::size_t>(i * 6 + i)] = kUnknownVariance;
    estimate.twist.covariance[static_cast<std::size_t>(i * 6 + i)] = kUnknownVariance;
  }
  estimate.solver = "disparity";
  return estimate;
}

// The estimate of a detection: the port's position and covariance when found, the stage that decided.
docking_msgs::TargetEstimate toEstimate(const std_msgs::Header& header, const disparity::Detection& detection) {
  docking_msgs::TargetEstimate estimate = blankEstimate(header);
  estimate.valid = detection.found;
  estimate.position_valid = detection.found;
  estimate.status = detection.found ? std::string() : detection.reason;
  estimate.reject_reason = rejectReasonOf(detection.found, detection.outcome);
  estimate.stage = static_cast<std::uint8_t>(detection.outcome.stage);
  estimate.stage_outcome = detection.outcome.code;
  if (!detection.found) return estimate;
  estimate.pose.pose.position.x = detection.position_m.x();
  estimate.pose.pose.position.y = detection.position_m.y();
  estimate.pose.pose.position.z = detection.position_m.z();
  for (int row = 0; row < 3; ++row) {
    for (int col = 0; col < 3; ++col) {
      estimate.pose.covariance[static_cast<std::size_t>(row * 6 + col)] = detection.covariance_m2(row, col);
    }
  }
  estimate.range_m = detection.range_m;
  estimate.disparity_px = detection.disparity_px;
  estimate.feature_inliers = static_cast<std::uint32_t>(detection.blob_pixels);
  return estimate;
}

}  // namespace

void DisparityDetectorNodelet::onInit() {
  nh_ = getNodeHandle();
  private_nh_ = getPrivateNodeHandle();

  disparity::DisparityDetectorSettings settings;
  try {
    settings = loadSettings();
  } catch (const std::exception& error) {
    // Thrown on: the nodelet loader catches it and refuses this nodelet (see mono_pose_nodelet.cpp);
    // perception_host says so and runs without it, a `nodelet load` process exits non-zero. The loader
    // logs the exception's message at DEBUG only: said here first.
    NODELET_FATAL("disparity_detector: %s", error.what());
    throw;
  }
  {
    std::lock_guard<std::mutex> lock(pause_mutex_);
    near_.setParams(toPauseParams(settings.pause));
  }

  // Live tuning: the server starts from the declared defaults and the parameter server's values, the same
  // as `settings`; its first callback applies them.
  reconfigure_server_ = std::make_unique<dynamic_reconfigure::Server<Config>>(reconfigure_mutex_,
                                                                              private_nh_);
  reconfigure_server_->setCallback(
      [this](Config& new_config, uint32_t level) { onReconfigure(new_config, level); });

  diagnostics_ = std::make_unique<diagnostic_updater::Updater>(nh_, private_nh_, getName());
  diagnostics_->setHardwareID("stereo_disparity");
  diagnostics_->add("disparity_detector", this, &DisparityDetectorNodelet::produceDiagnostics);
  diagnostics_timer_ = nh_.createTimer(ros::Duration(1.0),
                                       [this](const ros::TimerEvent&) { diagnostics_->update(); });

  advertise();
}

// Outputs first, with connection callbacks that (un)subscribe the inputs on demand.
void DisparityDetectorNodelet::advertise() {
  std::lock_guard<std::mutex> lock(connection_mutex_);
  image_transport_ = std::make_unique<image_transport::ImageTransport>(nh_);
  auto connection_changed = [this](const ros::SingleSubscriberPublisher&) { updateSubscriptions(); };
  estimate_publisher_ = nh_.advertise<docking_msgs::TargetEstimate>(
      docking_msgs::topics::kDisparityEstimate, 5, connection_changed, connection_changed);
  auto image_connection_changed = [this](const image_transport::SingleSubscriberPublisher&) {
    updateSubscriptions();
  };
  // The debug image sits beside the estimate: perception/disparity/debug_image.
  const std::string debug_topic =
      ros::names::parentNamespace(docking_msgs::topics::kDisparityEstimate) + "/debug_image";
  debug_publisher_ = image_transport_->advertise(debug_topic, 1, image_connection_changed,
                                                 image_connection_changed);
  // The arbiter's output says when this stage may rest (near, on a monocular pose); the timer resumes it
  // when that output stops arriving.
  fused_subscriber_ = nh_.subscribe(docking_msgs::topics::kTargetEstimate, 1,
                                    &DisparityDetectorNodelet::onFusedEstimate, this,
                                    ros::TransportHints().tcpNoDelay());  // small and timely: no Nagle delay
  pause_timer_ = nh_.createTimer(ros::Duration(kPauseCheckPeriodS),
                                 [this](const ros::TimerEvent&) { updateSubscriptions(); });
  NODELET_INFO("disparity_detector: publishing %s and %s; subscribing %s only while they have "
               "subscribers and the target is not near (%s)",
               estimate_publisher_.getTopic().c_str(), debug_publisher_.getTopic().c_str(),
               nh_.resolveName(docking_msgs::topics::kStereoDisparity).c_str(),
               fused_subscriber_.getTopic().c_str());
}

void DisparityDetectorNodelet::onFusedEstimate(const docking_msgs::TargetEstimateConstPtr& fused) {
  const bool monocular = fused->selected_source == docking_msgs::TargetEstimate::SOURCE_MONO_VISIBLE ||
                         fused->selected_source == docking_msgs::TargetEstimate::SOURCE_MONO_IR;
  {
    std::lock_guard<std::mutex> lock(pause_mutex_);
    near_.onFusedEstimate(ros::Time::now().toSec(), fused->valid && fused->position_valid, monocular,
                          fused->range_m);
  }
  updateSubscriptions();
}

disparity::DisparityDetectorSettings DisparityDetectorNodelet::loadSettings() {
  disparity::DisparityDetectorSettings settings;
  docking_settings::loadSettings(private_nh_, settings);
  docking_settings::warnUnknownKeys(private_nh_, settings, {"target_yaml", "robot_yaml", "matcher"});
  // The matcher's blind left band is its largest disparity (in each DisparityImage) plus half its correlation
  // window, rounded up: read from the matcher's own settings (config/stereo_image_proc.yaml, as ~matcher).
  const docking_settings::ParamReader matcher(ros::NodeHandle(private_nh_, "matcher"));
  const int correlation_window_px = matcher.requireInRange<int>("correlation_window_size", 1, 255);
  blind_band_extra_px_ = (correlation_window_px + 1) / 2;
  // The mockup's size for the shape check and its face print for the appearance check: the same
  // target.yaml the simulator and mono_pose read.
  const auto target_yaml = docking_settings::ParamReader(private_nh_).require<std::string>("target_yaml");
  // The cameras' and the port's heights (level_floor's floor cut and height gate): robot.yaml and target.yaml.
  const auto robot_yaml = docking_settings::ParamReader(private_nh_).require<std::string>("robot_yaml");
  disparity::RigGeometry rig;
  try {
    rig = disparity::loadRigGeometry(robot_yaml, target_yaml, correlation_window_px);
  } catch (const std::exception& error) {
    docking_settings::ParamReader(private_nh_).invalid("robot_yaml", error.what());
  }
  disparity::TargetShape shape;
  try {
    shape = disparity::loadTargetShape(target_yaml);
    const mono::TargetModel model = mono::TargetModel::loadFromYaml(target_yaml);
    appearance_check_ = std::make_unique<disparity::FaceAppearanceCheck>(model.textureGray(), model.faceWidth(),
                                                                        model.faceHeight());
  } catch (const std::exception& error) {
    docking_settings::ParamReader(private_nh_).invalid("target_yaml", error.what());
  }
  docking_settings::ParamReader(private_nh_).validated([&] {
    std::lock_guard<std::mutex> lock(state_mutex_);
    detector_ = disparity::DisparityDetector(settings.detector, shape, rig);
    track_gate_.setParams(settings.track);
    settings_ = settings;
  });
  return settings;
}

duty::FusedRangeConditionParams DisparityDetectorNodelet::toPauseParams(const disparity::PauseParams& pause) {
  duty::FusedRangeConditionParams p;
  p.range_m = pause.inside_range_m;
  p.hysteresis_m = kPauseHysteresisM;
  p.max_fused_age_s = kPauseMaxFusedAgeS;
  return p;
}

void DisparityDetectorNodelet::onReconfigure(Config& config, uint32_t /*level*/) {
  dynamic_reconfigure::Config message;
  config.__toMessage__(message);
  std::lock_guard<std::mutex> lock(state_mutex_);
  disparity::DisparityDetectorSettings settings = settings_;
  docking_settings::applyReconfigure(message, settings);
  try {
    docking_settings::validateSettings(settings);
    disparity::validate(settings.detector, detector_.shape(), detector_.rig());
  } catch (const std::invalid_argument& error) {
    // Keep running with the last good values, and show them back to dynamic_reconfigure clients (dynparam get).
    NODELET_ERROR("disparity_detector: reconfigure rejected, keeping the previous values: %s", error.what());
    dynamic_reconfigure::Config kept = docking_settings::toReconfigure(settings_);
    config.__fromMessage__(kept);
    return;
  }
  detector_.setParams(settings.detector);
  track_gate_.setParams(settings.track);
  settings_ = settings;
  {
    std::lock_guard<std::mutex> pause_lock(pause_mutex_);
    near_.setParams(toPauseParams(settings.pause));
  }
}

void DisparityDetectorNodelet::updateSubscriptions() {
  duty::FusedRangeState near_state;
  {
    std::lock_guard<std::mutex> lock(pause_mutex_);
    near_state = near_.state(ros::Time::now().toSec());
    near_state_ = near_state;
  }
  std::lock_guard<std::mutex> lock(connection_mutex_);
  const bool wanted =
      (estimate_publisher_.getNumSubscribers() > 0 || debug_publisher_.getNumSubscribers() > 0) &&
      near_state != duty::FusedRangeState::kHolds;
  if (wanted && !disparity_subscriber_) {
    disparity_subscriber_ = nh_.subscribe(docking_msgs::topics::kStereoDisparity, 1,
                                          &DisparityDetectorNodelet::onDisparity, this);
    camera_info_subscriber_ = nh_.subscribe(docking_msgs::topics::kStereoFarFullLeftCameraInfo, 1,
                                            &DisparityDetectorNodelet::onCameraInfo, this);
    left_image_subscriber_ = nh_.subscribe(docking_msgs::topics::kStereoFarFullLeftImageRect, 1,
                                           &DisparityDetectorNodelet::onLeftImage, this);
    NODELET_DEBUG("disparity_detector: subscribed to %s", disparity_subscriber_.getTopic().c_str());
  } else if (!wanted && disparity_subscriber_) {
    disparity_subscriber_.shutdown();
    camera_info_subscriber_.shutdown();
    left_image_subscriber_.shutdown();
    disparity_subscriber_ = ros::Subscriber();
    camera_info_subscriber_ = ros::Subscriber();
    left_image_subscriber_ = ros::Subscriber();
    NODELET_DEBUG("disparity_detector: unsubscribed from the disparity (near: %s)", duty::describe(near_state));
  }
}

void DisparityDetectorNodelet::onCameraInfo(const sensor_msgs::CameraInfoConstPtr& info) {
  std::lock_guard<std::mutex> lock(state_mutex_);
  if (isWindow(*info)) {
    recent_window_infos_.push_back(info);
    while (recent_window_infos_.size() > kRecentWindowInfos) recent_window_infos_.pop_front();
    last_window_info_arrival_s_ = ros::Time::now().toSec();
    return;
  }
  camera_info_ = info;
}

void DisparityDetectorNodelet::onLeftImage(const sensor_msgs::ImageConstPtr& image) {
  std::lock_guard<std::mutex> lock(state_mutex_);
  recent_left_images_.push_back(image);
  while (recent_left_images_.size() > kRecentLeftImages) recent_left_images_.pop_front();
}

void DisparityDetectorNodelet::confirmAppearance(const stereo_msgs::DisparityImage& message, const cv::Mat& disparity,
                                                 const disparity::DetectorParams& params,
                                                 const disparity::StereoGeometry& geometry,
                                                 disparity::Detection* detection) {
  if (!params.appearance.check_enabled || !detection->found || !appearance_check_) return;
  sensor_msgs::ImageConstPtr left;
  {
    std::lock_guard<std::mutex> lock(state_mutex_);
    for (auto it = recent_left_images_.rbegin(); it != recent_left_images_.rend(); ++it) {
      if ((*it)->header.stamp == message.header.stamp && (*it)->width == message.image.width &&
          (*it)->height == message.image.height) {
        left = *it;
        break;
      }
    }
  }
  cv::Mat left_grey;
  if (left && left->encoding == sensor_msgs::image_encodings::MONO8) {
    left_grey = cv_bridge::toCvShare(left, sensor_msgs::image_encodings::MONO8)->image;
  }
  if (left_grey.empty()) {
    std::lock_guard<std::mutex> lock(state_mutex_);
    ++appearance_without_image_;
    last_appearance_ = "no mono8 left image of the disparity's stamp and size: appearance not checked";
    return;
  }
  const disparity::AppearanceResult result =
      disparity::confirmByAppearance(*appearance_check_, left_grey, disparity, geometry, params.appearance,
                                     detection);
  std::lock_guard<std::mutex> lock(state_mutex_);
  if (result.verdict == disparity::AppearanceVerdict::kNotTheTarget) ++appearance_rejections_;
  if (disparity::isUnjudged(result.verdict)) ++appearance_unjudged_;
  last_appearance_ = result.reason;
}

void DisparityDetectorNodelet::publishInvalidInput(const stereo_msgs::DisparityImage& message,
                                                   disparity::StageOutcome outcome, const std::string& status,
                                                   double cpu_start_ms) {
  NODELET_ERROR_THROTTLE(5.0, "disparity_detector: %s", status.c_str());
  docking_msgs::TargetEstimate estimate = blankEstimate(message.header);
  estimate.status = status;
  estimate.reject_reason = docking_msgs::TargetEstimate::REJECT_BAD_INPUT;
  estimate.stage = static_cast<std::uint8_t>(outcome.stage);
  estimate.stage_outcome = outcome.code;
  estimate.processing_time_ms = threadCpuMs() - cpu_start_ms;
  {
    std::lock_guard<std::mutex> lock(state_mutex_);
    last_input_error_ = status;
  }
  recordOutcome(outcome, false, status, estimate.processing_time_ms);
  publishEstimate(estimate);
}

// Nothing a disparity image contains may end the manager: whatever the detector throws (cv::Exception
// is a std::exception) drops that image as invalid input, and the next one is processed.
void DisparityDetectorNodelet::onDisparity(const stereo_msgs::DisparityImageConstPtr& message) {
  const double cpu_start_ms = threadCpuMs();
  try {
    processDisparity(message);
  } catch (const std::exception& e) {
    try {
      publishInvalidInput(*message, disparity::InputOutcome::kDropped,
                          std::string("disparity image dropped: ") + e.what(), cpu_start_ms);
    } catch (const std::exception& again) {
      NODELET_ERROR_THROTTLE(5.0, "disparity_detector: could not report a dropped image: %s", again.what());
    }
  }
}

// The stages (stages.h), in order: the message (1), the detector (1-5), the appearance check (6), the track
// gate (7), the estimate's own check (8); the first that does not pass decides, and goes on the wire.
void DisparityDetectorNodelet::processDisparity(const stereo_msgs::DisparityImageConstPtr& message) {
  const double cpu_start_ms = threadCpuMs();
  std::string problem;
  const disparity::StageOutcome input = checkMessage(*message, &problem);
  if (!input.passed()) return publishInvalidInput(*message, input, problem, cpu_start_ms);
  Frame frame;
  if (!prepareFrame(*message, &frame, &problem)) {
    return publishInvalidInput(*message, disparity::InputOutcome::kNoWindowCameraInfo, problem, cpu_start_ms);
  }
  // Zero-copy view of the message data (kept alive by `message` for this callback).
  const sensor_msgs::Image& image = message->image;
  const cv::Mat disparity(static_cast<int>(image.height), static_cast<int>(image.width), CV_32FC1,
                          const_cast<std::uint8_t*>(image.data.data()), image.step);
  disparity::Detection detection =
      frame.detector.detect(disparity, frame.geometry, message->min_disparity, message->max_disparity + 1.0,
                            frame.valid_region, frame.hint, frame.window);
  confirmAppearance(*message, disparity, frame.detector.params(), frame.geometry, &detection);
  applyTrackGate(message->header.stamp.toSec(), &detection);
  docking_msgs::TargetEstimate estimate = toEstimate(message->header, detection);
  publishDebugImage(*message, disparity, detection, kDebugDisplayMaxDisparityPx);
  checkOutput(&detection, &estimate);
  estimate.processing_time_ms = threadCpuMs() - cpu_start_ms;
  recordOutcome(detection.outcome, detection.found, detection.reason, estimate.processing_time_ms);
  if (detection.found) {
    std::lock_guard<std::mutex> lock(state_mutex_);
    last_range_m_ = detection.range_m;
  }
  publishEstimate(estimate);
}

// Stage 7: the tracked target's gate; a detection it lets through has passed every stage so far.
void DisparityDetectorNodelet::applyTrackGate(double stamp_s, disparity::Detection* detection) {
  {
    std::lock_guard<std::mutex> lock(state_mutex_);
    *detection = track_gate_.apply(stamp_s, *detection);
  }
  if (detection->found) detection->outcome = disparity::TrackOutcome::kPassed;
}

// Stage 8: what the arbiter would refuse (a NaN, a bad covariance) leaves here as not valid, with the code.
void DisparityDetectorNodelet::checkOutput(disparity::Detection* detection, docking_msgs::TargetEstimate* estimate) {
  const auto own_problem = docking_msgs::checks::withdrawIfMalformed(estimate);
  if (own_problem != docking_msgs::checks::EstimateProblem::kNone) {
    NODELET_ERROR_THROTTLE(5.0, "disparity_detector: estimate withdrawn: %s",
                           docking_msgs::checks::estimateProblemName(own_problem));
    detection->found = false;
    detection->outcome = disparity::OutputOutcome::kWithdrawn;
    detection->reason = estimate->status;
  } else if (detection->found) {
    detection->outcome = disparity::OutputOutcome::kPassed;
  }
  estimate->stage = static_cast<std::uint8_t>(detection->outcome.stage);
  estimate->stage_outcome = detection->outcome.code;
}

bool DisparityDetectorNodelet::prepareFrame(const stereo_msgs::DisparityImage& message, Frame* frame,
                                            std::string* problem) {
  const sensor_msgs::Image& image = message.image;
  sensor_msgs::CameraInfoConstPtr camera_info, window_info;
  bool windows_recently = false;
  {
    std::lock_guard<std::mutex> lock(state_mutex_);
    frame->settings = settings_;
    frame->detector = detector_;
    camera_info = camera_info_;
    window_info = windowInfoOf(recent_window_infos_, message.header.stamp, image.width, image.height);
    if (window_info) ++window_frames_;
    // A disparity of the full image's size is not a window: it may be read without a camera_info.
    const auto& last_window = recent_window_infos_.empty() ? nullptr : recent_window_infos_.back();
    windows_recently = last_window && ros::Time::now().toSec() - last_window_info_arrival_s_ < kWindowInfoMemoryS &&
                       (image.width != last_window->width || image.height != last_window->height);
    last_input_error_.clear();
  }
  if (window_info) {
    camera_info = window_info;
    frame->window.offset = cv::Point(static_cast<int>(window_info->roi.x_offset),
                                     static_cast<int>(window_info->roi.y_offset));
    frame->window.full_size = cv::Size(static_cast<int>(window_info->width), static_cast<int>(window_info->height));
  }
  if (!cameraModel(message, camera_info, windows_recently, frame, problem)) return false;
  frame->valid_region = validRegionOf(message, blind_band_extra_px_);
  // The tracked target tells the search which target-shaped blob to prefer, then judges the result.
  // The gate is the one piece of state across frames (frames arrive in order on one subscriber).
  std::lock_guard<std::mutex> lock(state_mutex_);
  frame->hint = track_gate_.hint(message.header.stamp.toSec());
  return true;
}

// The rectified model: f and B from the message; the principal point from the far stage's left camera_info
// when it is of the disparity's size (image_geometry: a window's region of interest shifts it), else the image
// centre. False (and why) for a window's disparity whose camera_info is missing.
bool DisparityDetectorNodelet::cameraModel(const stereo_msgs::DisparityImage& message,
                                           const sensor_msgs::CameraInfoConstPtr& camera_info, bool windows_recently,
                                           Frame* frame, std::string* problem) {
  const sensor_msgs::Image& image = message.image;
  disparity::StereoGeometry& geometry = frame->geometry;
  geometry.focal_px = message.f;
  geometry.baseline_m = message.T;
  geometry.cx_px = (image.width - 1) / 2.0;
  geometry.cy_px = (image.height - 1) / 2.0;
  image_geometry::PinholeCameraModel model;
  const bool have_model =
      camera_info && model.fromCameraInfo(camera_info) && model.fx() > 0.0 &&
      model.reducedResolution() == cv::Size(static_cast<int>(image.width), static_cast<int>(image.height));
  if (have_model) {
    geometry.cx_px = model.cx();
    geometry.cy_px = model.cy();
    if (std::abs(model.fx() - message.f) > 0.01 * message.f) {
      NODELET_WARN_THROTTLE(30.0, "disparity_detector: left camera_info fx %.1f differs from the DisparityImage f "
                            "%.1f; using f from the disparity", model.fx(), message.f);
    }
  } else if (windows_recently) {
    // The far stage is sending windows: a disparity smaller than the image, of no known size, is one whose
    // camera_info has not arrived (or was lost). Read with the image centre it would be placed wrongly:
    // dropped instead.
    std::ostringstream missing;
    missing << "no camera_info for the " << image.width << "x" << image.height << " disparity image at "
            << message.header.stamp << " (the far stage's tracking window's camera_info has not arrived)";
    *problem = missing.str();
    return false;
  } else if (!warned_no_camera_info_) {
    warned_no_camera_info_ = true;
    NODELET_WARN("disparity_detector: no camera_info of the disparity's size (%ux%u) on %s yet; using the image "
                 "centre (%.1f, %.1f) as the principal point", image.width, image.height,
                 camera_info_subscriber_.getTopic().c_str(), geometry.cx_px, geometry.cy_px);
  }
  return true;
}

void DisparityDetectorNodelet::publishDebugImage(const stereo_msgs::DisparityImage& message, const cv::Mat& disparity,
                                                 const disparity::Detection& detection, double display_max_px) {
  if (debug_publisher_.getNumSubscribers() == 0) return;
  const double debug_start_ms = threadCpuMs();
  cv_bridge::CvImage debug(message.header, sensor_msgs::image_encodings::BGR8,
                           disparity::renderDebugImage(disparity, detection, display_max_px));
  debug_publisher_.publish(debug.toImageMsg());
  recordDebugImage(threadCpuMs() - debug_start_ms);
}

void DisparityDetectorNodelet::publishEstimate(const docking_msgs::TargetEstimate& estimate) {
  estimate_publisher_.publish(estimate);
  if (estimate.header.stamp.isZero()) return;
  const double latency_s = (ros::Time::now() - estimate.header.stamp).toSec();
  std::lock_guard<std::mutex> lock(state_mutex_);
  latency_.add(latency_s);
}

void DisparityDetectorNodelet::recordOutcome(disparity::StageOutcome outcome, bool found, const std::string& reason,
                                             double processing_ms) {
  std::lock_guard<std::mutex> lock(state_mutex_);
  ++frames_;
  ++outcome_counts_[{outcome.stage, outcome.code}];
  if (found) {
    ++detections_;
  } else {
    last_rejection_ = reason;
  }
  last_processing_ms_ = processing_ms;
  recent_found_.push_back(found);
  while (recent_found_.size() > kDiagnosticWindowFrames) {
    recent_found_.pop_front();
  }
}

void DisparityDetectorNodelet::recordDebugImage(double cpu_ms) {
  std::lock_guard<std::mutex> lock(state_mutex_);
  ++debug_images_;
  debug_image_cpu_ms_total_ += cpu_ms;
}

// The diagnostics' one line: idle, paused, bad input, or the detection rate against min_detection_rate_ok.
void DisparityDetectorNodelet::summarize(diagnostic_updater::DiagnosticStatusWrapper& status, bool paused,
                                         double rate) const {
  if (!disparity_subscriber_ && paused) {
    status.summary(diagnostic_msgs::DiagnosticStatus::OK, "paused: target near, the arbiter on a monocular pose");
  } else if (!disparity_subscriber_) {
    status.summary(diagnostic_msgs::DiagnosticStatus::OK, "idle: no subscribers");
  } else if (!last_input_error_.empty()) {
    status.summary(diagnostic_msgs::DiagnosticStatus::ERROR, "bad input: " + last_input_error_);
  } else if (recent_found_.empty()) {
    status.summary(diagnostic_msgs::DiagnosticStatus::WARN, "no disparity image received yet");
  } else if (rate < settings_.min_detection_rate_ok) {
    std::ostringstream summary;
    summary.precision(2);
    summary << "detection rate " << rate << " < " << settings_.min_detection_rate_ok
            << "; last rejection: " << last_rejection_;
    status.summary(diagnostic_msgs::DiagnosticStatus::WARN, summary.str());
  } else {
    std::ostringstream summary;
    summary.precision(2);
    summary << "detecting, rate " << rate;
    status.summary(diagnostic_msgs::DiagnosticStatus::OK, summary.str());
  }
}

void DisparityDetectorNodelet::produceDiagnostics(
    diagnostic_updater::DiagnosticStatusWrapper& status) {
  std::lock_guard<std::mutex> lock(state_mutex_);
  const double rate =
      recent_found_.empty()
          ? 0.0
          : static_cast<double>(std::count(recent_found_.begin(), recent_found_.end(), true)) /
                static_cast<double>(recent_found_.size());
  status.add("frames", frames_);
  status.add("frames in a tracking window", window_frames_);
  status.add("detections", detections_);
  status.add("detection rate (last frames)", rate);
  status.add("window frames", recent_found_.size());
  status.add("last rejection reason", last_rejection_.empty() ? "(none)" : last_rejection_);
  // Every frame's deciding stage and its outcome (stages.h), e.g. "outcome band_search/not_target_shaped".
  for (const auto& entry : outcome_counts_) {
    const disparity::StageOutcome outcome(entry.first.first, entry.first.second);
    status.add(std::string("outcome ") + disparity::stageName(outcome.stage) + "/" + disparity::outcomeName(outcome),
               entry.second);
  }
  status.add("last range m", last_range_m_);
  status.add("appearance rejections", appearance_rejections_);
  status.add("appearance not judged (glare, dark)", appearance_unjudged_);
  status.add("appearance without a left image", appearance_without_image_);
  status.add("last appearance check", last_appearance_.empty() ? "(none)" : last_appearance_);
  status.add("last processing ms (CPU)", last_processing_ms_);
  status.add("subscribed", static_cast<bool>(disparity_subscriber_));
  duty::FusedRangeState near_state;
  {
    std::lock_guard<std::mutex> pause_lock(pause_mutex_);
    near_state = near_state_;
  }
  const bool paused = near_state == duty::FusedRangeState::kHolds;
  status.add("paused", paused);
  status.add("target near on a monocular pose", duty::describe(near_state));
  status.add("debug images drawn", debug_images_);
  status.add("debug image CPU ms (mean)", debug_images_ > 0 ? debug_image_cpu_ms_total_ / debug_images_ : 0.0);
  docking_msgs::addLatency(status, "image->estimate", latency_);

  summarize(status, paused, rate);
}

}  // namespace docking_perception

PLUGINLIB_EXPORT_CLASS(docking_perception::DisparityDetectorNodelet, nodelet::Nodelet)
