#include "capture_nodelet.h"

#include <docking_msgs/names.h>
#include <docking_perception/camera/calibration_check.h>
#include <docking_perception/camera/ir_camera_settings.h>
#include <docking_perception/camera/stereo_camera_settings.h>
#include <docking_settings/ros_loader.h>

#include <cv_bridge/cv_bridge.h>
#include <pluginlib/class_list_macros.hpp>
#include <ros/names.h>

#include <chrono>
#include <stdexcept>

namespace docking_perception {
namespace {

double steadySeconds() {
  return std::chrono::duration<double>(std::chrono::steady_clock::now().time_since_epoch()).count();
}

}  // namespace

CaptureNodelet::CaptureNodelet(std::vector<CameraChannelDefaults> channels, camera::ColourMode colour_mode)
    : colour_mode_(colour_mode) {
  for (auto& defaults : channels) {
    Channel channel;
    channel.defaults = std::move(defaults);
    channels_.push_back(std::move(channel));
  }
}

CaptureNodelet::~CaptureNodelet() {
  stop_ = true;
  if (capture_thread_.joinable()) capture_thread_.join();
}

void CaptureNodelet::readParameters() {
  const ros::NodeHandle& pnh = getPrivateNodeHandle();
  const docking_settings::ParamReader reader(pnh);
  const CameraSettings loaded = loadSettings(pnh);
  const camera::CaptureNodeSettings& c = loaded.capture;
  settings_.width = c.width;
  settings_.height = c.height;
  settings_.fps = rate_hz_ = c.rate_hz;
  settings_.fourcc = c.fourcc;
  settings_.loop_files = c.loop_files;
  settings_.max_consecutive_empty = c.max_consecutive_empty;
  reader.validated([&] { camera::validateCaptureSettings(settings_); });
  backoff_ = camera::BackoffParams{c.retry.initial_s, c.retry.max_s, c.retry.factor};
  reader.validated([&] { camera::validateBackoffParams(backoff_); });
  rate_tolerance_ = c.rate_tolerance;
  for (std::size_t i = 0; i < channels_.size(); ++i) readChannel(reader, loaded.channels.at(i), channels_[i]);
}

void CaptureNodelet::readChannel(const docking_settings::ParamReader& reader, const camera::ChannelSettings& settings,
                                 Channel& channel) {
  const std::string& prefix = channel.defaults.param_prefix;
  try {
    channel.source = camera::parseSourceSpec(settings.source);
  } catch (const std::invalid_argument& e) {
    reader.invalid(prefix + "source", e.what());
  }
  channel.frame_id = settings.frame_id.empty() ? channel.defaults.frame_id : settings.frame_id;
  if (!settings.camera_name.empty()) channel.defaults.camera_name = settings.camera_name;
  channel.calibration_url = settings.camera_info_url;
}

CaptureNodelet::CameraSettings StereoCameraNodelet::loadSettings(const ros::NodeHandle& pnh) const {
  camera::StereoCameraSettings s;
  docking_settings::loadSettings(pnh, s);
  docking_settings::warnUnknownKeys(pnh, s);
  return {s.capture, {s.left, s.right}};
}

CaptureNodelet::CameraSettings IrCameraNodelet::loadSettings(const ros::NodeHandle& pnh) const {
  camera::IrCameraSettings s;
  docking_settings::loadSettings(pnh, s);
  docking_settings::warnUnknownKeys(pnh, s);
  return {s.capture, {s.channel}};
}

void CaptureNodelet::onInit() {
  ros::NodeHandle& nh = getNodeHandle();
  try {
    readParameters();
  } catch (const docking_settings::ConfigError& e) {
    NODELET_FATAL("%s: not starting", e.what());
    throw;  // nodelet::Loader drops the nodelet; the standalone executable parks (docking_settings::runNode)
  }
  image_transport_ = std::make_unique<image_transport::ImageTransport>(nh);
  std::vector<camera::SourceSpec> sources;
  std::string hardware_id;
  for (Channel& channel : channels_) {
    loadCalibration(channel);
    channel.publisher = image_transport_->advertiseCamera(channel.defaults.image_topic, 1);
    sources.push_back(channel.source);
    hardware_id += (hardware_id.empty() ? "" : " + ") + channel.source.text;
    NODELET_INFO("%s: %s -> %s (frame %s, calibration %s)", channel.defaults.camera_name.c_str(),
                 channel.source.describe().c_str(), nh.resolveName(channel.defaults.image_topic).c_str(),
                 channel.frame_id.c_str(), channel.calibration_file.c_str());
  }
  rig_ = std::make_unique<camera::CaptureRig>(sources, settings_, backoff_);
  startDiagnostics(hardware_id);
  capture_thread_ = std::thread(&CaptureNodelet::captureLoop, this);
}

void CaptureNodelet::loadCalibration(Channel& channel) {
  // camera_info_manager lives in the camera's namespace (stereo/left), where cameracalibrator.py calls
  // its set_camera_info service.
  const std::string camera_ns = ros::names::parentNamespace(channel.defaults.image_topic);
  ros::NodeHandle camera_nh(getNodeHandle(), camera_ns);
  channel.info_manager = std::make_shared<camera_info_manager::CameraInfoManager>(
      camera_nh, channel.defaults.camera_name);
  if (!channel.calibration_url.empty() && !channel.info_manager->validateURL(channel.calibration_url)) {
    const std::string param = getPrivateNodeHandle().resolveName(channel.defaults.param_prefix + "camera_info_url");
    NODELET_FATAL("parameter %s: '%s' is not a valid calibration URL (file:///path.yaml): not starting",
                  param.c_str(), channel.calibration_url.c_str());
    throw docking_settings::ConfigError(param, docking_settings::ConfigProblem::kInvalid, "not a calibration URL");
  }
  channel.info_manager->loadCameraInfo(channel.calibration_url);
  channel.calibration_file = channel.calibration_url.empty()
                                 ? "(camera_info_manager default for " + channel.defaults.camera_name + ")"
                                 : camera::calibrationFileFromUrl(channel.calibration_url);
  const std::string& calibration_file = channel.calibration_file;
  if (!channel.info_manager->isCalibrated()) {
    NODELET_WARN("%s: no calibration loaded from '%s': publishing an uncalibrated camera_info (see the README "
                 "to calibrate)", channel.defaults.camera_name.c_str(), calibration_file.c_str());
  } else {
    const auto info = channel.info_manager->getCameraInfo();
    const std::string problem = camera::calibrationSizeProblem(
        calibration_file, static_cast<int>(info.width), static_cast<int>(info.height), settings_.width,
        settings_.height, "the configured resolution (~width, ~height)");
    if (!problem.empty() && channel.source.isLiveDevice()) {
      NODELET_ERROR("%s: %s", getName().c_str(), problem.c_str());
    }
  }
}

void CaptureNodelet::startDiagnostics(const std::string& hardware_id) {
  diagnostics_ = std::make_unique<diagnostic_updater::Updater>(getNodeHandle(), getPrivateNodeHandle(), getName());
  diagnostics_->setHardwareID(hardware_id);
  diagnostics_->add(docking_msgs::diagnostics::kCameraCapture, this, &CaptureNodelet::diagnoseCapture);
  min_rate_hz_ = rate_hz_;
  max_rate_hz_ = rate_hz_;
  publish_rate_ = std::make_unique<diagnostic_updater::FrequencyStatus>(
      diagnostic_updater::FrequencyStatusParam(&min_rate_hz_, &max_rate_hz_, rate_tolerance_, 10), "publishing rate");
  diagnostics_->add(*publish_rate_);
}

void CaptureNodelet::captureLoop() {
  const double period_s = 1.0 / rate_hz_;
  double next_frame_s = steadySeconds();
  while (!stop_ && ros::ok()) {
    const double now_s = steadySeconds();
    double sleep_until_s = now_s + std::min(period_s, 0.1);
    try {
      ros::Time stamp;
      const camera::CaptureOutcome outcome = rig_->capture(now_s, [&stamp] { stamp = ros::Time::now(); });
      switch (outcome.status) {
        case camera::CaptureStatus::kFrames:
          handleFrames(outcome.frames, stamp);
          next_frame_s = std::max(next_frame_s + period_s, now_s);
          sleep_until_s = next_frame_s;
          break;
        case camera::CaptureStatus::kEmptyFrame:
          ++empty_frames_total_;
          ++empty_frames_since_report_;
          NODELET_WARN_THROTTLE(5.0, "%s: %s: frame skipped (%lu empty frames so far)", getName().c_str(),
                                outcome.message.c_str(), empty_frames_total_);
          break;
        case camera::CaptureStatus::kWaiting:
          state_ = State::kWaiting;
          state_message_ = outcome.message;
          retry_in_s_ = std::max(0.0, outcome.retry_at_s - now_s);
          if (outcome.new_failure) {
            NODELET_ERROR("%s: %s; retrying in %.1f s (failure %d in a row)", getName().c_str(),
                          outcome.message.c_str(), retry_in_s_, rig_->consecutiveFailures());
          }
          break;
        case camera::CaptureStatus::kRestarted:
          NODELET_DEBUG("%s", outcome.message.c_str());
          sleep_until_s = now_s;
          break;
        case camera::CaptureStatus::kEndOfStream:
          if (state_ != State::kEnded) {
            NODELET_WARN("%s: %s: no more frames", getName().c_str(), outcome.message.c_str());
          }
          state_ = State::kEnded;
          state_message_ = outcome.message;
          break;
      }
    } catch (const std::exception& e) {
      // OpenCV or cv_bridge on a frame we did not expect: report it, keep the node alive.
      NODELET_ERROR_THROTTLE(5.0, "%s: capture failed: %s", getName().c_str(), e.what());
      state_message_ = std::string("capture failed: ") + e.what();
    }
    diagnostics_->update();
    while (!stop_ && steadySeconds() < sleep_until_s) {
      std::this_thread::sleep_for(std::chrono::duration<double>(std::min(0.05, sleep_until_s - steadySeconds())));
    }
  }
}

void CaptureNodelet::handleFrames(const std::vector<cv::Mat>& frames, const ros::Time& stamp) {
  std::vector<camera::PublishableFrame> images;
  std::vector<sensor_msgs::CameraInfo> infos;
  for (size_t i = 0; i < channels_.size(); ++i) {
    const Channel& channel = channels_[i];
    camera::PublishableFrame image = camera::toPublishable(frames[i], colour_mode_);
    if (!image.ok()) {
      state_ = State::kRefused;
      state_message_ = channel.source.describe() + ": " + image.error;
      ++frames_refused_;
      NODELET_ERROR_THROTTLE(5.0, "%s: %s", getName().c_str(), state_message_.c_str());
      return;
    }
    sensor_msgs::CameraInfo info = channel.info_manager->getCameraInfo();
    const std::string problem = camera::calibrationSizeProblem(
        channel.calibration_file, static_cast<int>(info.width), static_cast<int>(info.height), image.image.cols, image.image.rows,
        "the frames of " + channel.source.describe());
    if (!problem.empty()) {
      state_ = State::kRefused;
      state_message_ = problem;
      ++frames_refused_;
      NODELET_ERROR_THROTTLE(10.0, "%s: %s", getName().c_str(), problem.c_str());
      return;
    }
    if (info.width == 0) {  // uncalibrated: still say how big the images are
      info.width = static_cast<uint32_t>(image.image.cols);
      info.height = static_cast<uint32_t>(image.image.rows);
    }
    images.push_back(image);
    infos.push_back(info);
  }

  // One stamp for the whole set: the moment every source had grabbed.
  for (size_t i = 0; i < channels_.size(); ++i) {
    std_msgs::Header header;
    header.stamp = stamp;
    header.frame_id = channels_[i].frame_id;
    sensor_msgs::ImagePtr image_msg = cv_bridge::CvImage(header, images[i].encoding, images[i].image).toImageMsg();
    auto info_msg = boost::make_shared<sensor_msgs::CameraInfo>(infos[i]);
    info_msg->header = header;
    channels_[i].publisher.publish(image_msg, info_msg);
  }
  if (state_ != State::kStreaming) {
    NODELET_INFO("%s: streaming from %s", getName().c_str(), rig_->sources().front().describe().c_str());
  }
  state_ = State::kStreaming;
  state_message_.clear();
  ++frames_published_;
  publish_rate_->tick();
}

void CaptureNodelet::diagnoseCapture(diagnostic_updater::DiagnosticStatusWrapper& status) {
  using diagnostic_msgs::DiagnosticStatus;
  switch (state_) {
    case State::kStarting:
      status.summary(DiagnosticStatus::WARN, "starting");
      break;
    case State::kStreaming:
      if (empty_frames_since_report_ > 0) {
        status.summaryf(DiagnosticStatus::WARN, "streaming; %lu empty frames skipped", empty_frames_since_report_);
      } else {
        status.summary(DiagnosticStatus::OK, "streaming");
      }
      break;
    case State::kWaiting:
      status.summaryf(DiagnosticStatus::ERROR, "%s; retrying in %.1f s", state_message_.c_str(), retry_in_s_);
      break;
    case State::kRefused:
      status.summary(DiagnosticStatus::ERROR, state_message_);
      break;
    case State::kEnded:
      status.summary(DiagnosticStatus::WARN, state_message_ + ": no more frames");
      break;
  }
  empty_frames_since_report_ = 0;
  for (const Channel& channel : channels_) {
    status.add(channel.defaults.camera_name + " source", channel.source.describe());
  }
  status.add("consecutive failures", rig_->consecutiveFailures());
  status.add("frames published", frames_published_);
  status.add("frames refused", frames_refused_);
  status.add("empty frames", empty_frames_total_);
}

StereoCameraNodelet::StereoCameraNodelet()
    : CaptureNodelet({{"left/", docking_msgs::topics::kStereoLeftImageRaw, "stereo_left",
                       docking_msgs::frames::kStereoLeftOptical},
                      // Both images of the pair carry the left frame: stereo_image_proc requires it (the
                      // baseline is in the right calibration's projection matrix).
                      {"right/", docking_msgs::topics::kStereoRightImageRaw, "stereo_right",
                       docking_msgs::frames::kStereoLeftOptical}},
                     camera::ColourMode::kKeep) {}

IrCameraNodelet::IrCameraNodelet()
    : CaptureNodelet({{"", docking_msgs::topics::kIrImageRaw, "ir", docking_msgs::frames::kIrOptical}},
                     camera::ColourMode::kMono) {}

}  // namespace docking_perception

PLUGINLIB_EXPORT_CLASS(docking_perception::StereoCameraNodelet, nodelet::Nodelet)
PLUGINLIB_EXPORT_CLASS(docking_perception::IrCameraNodelet, nodelet::Nodelet)
