// far_stereo_rectify: the far stage's own rectified pair (issue 15). Pairs the left and right grey images
// (image_mono, with the guarded camera_info) by stamp and rectifies both (disparity/window_rectifier.h), at
// full resolution, published on stereo/far/full/{left,right}/{image_rect,camera_info} for the block matcher:
//   - the whole image while the target is being acquired (no fresh, valid fused estimate);
//   - only a window around the target (disparity/tracking_window.h) while the arbiter's fused estimate
//     (target/estimate) is fresh and valid (window_enabled), its camera_info saying where the window lies
//     (image_geometry's region of interest: roi = the window, the principal point shifted by its offset),
//     so that the matcher and the detector work on the window as on a smaller camera. The window's left
//     side leaves room for the matcher's search range (~matcher/{min_disparity,disparity_range,
//     correlation_window_size}, loaded from config/stereo_image_proc.yaml, the matcher's own file).
// The camera_info published beside each image is the rectified camera (K = P's 3x3, no distortion, R = I) at
// the calibrated size. Only pairs are rectified: the left camera's other frames pass through the
// synchroniser untouched. Lazy: subscribes while anything reads its output (the matcher, paused with the
// detector). A bad image or camera_info (wrong encoding or size, uncalibrated, binned or cropped input) drops
// that pair with a throttled error naming the problem, counted in diagnostics (WARN while pairs are being
// dropped, with the reason); the next pair is processed.
// Settings: declared in settings/far_stereo_rectify.yaml (config/far_stereo.yaml holds what differs from the
// defaults); and matcher/{min_disparity,disparity_range,correlation_window_size}, the matcher's own.
#include <memory>
#include <mutex>
#include <optional>
#include <sstream>
#include <string>

#include <diagnostic_updater/diagnostic_updater.h>
#include <message_filters/subscriber.h>
#include <message_filters/time_synchronizer.h>
#include <nodelet/nodelet.h>
#include <pluginlib/class_list_macros.hpp>
#include <ros/ros.h>
#include <sensor_msgs/CameraInfo.h>
#include <sensor_msgs/Image.h>
#include <sensor_msgs/image_encodings.h>

#include "docking_msgs/TargetEstimate.h"
#include "docking_msgs/names.h"
#include "docking_perception/disparity/window_rectifier.h"
#include "docking_perception/disparity/tracking_window.h"
#include "docking_settings/param_reader.h"
#include "docking_settings/ros_loader.h"

namespace docking_perception {
namespace disparity {

namespace {

constexpr int kSyncQueue = 5;  // left frames (30 Hz) kept while their right partner is on its way

// The camera of a guarded camera_info, or the reason it cannot be rectified.
std::optional<PinholeCalibration> calibrationOf(const sensor_msgs::CameraInfo& info, std::string* problem) {
  std::ostringstream why;
  if (info.binning_x > 1 || info.binning_y > 1) {
    why << "camera_info is already binned (" << info.binning_x << "x" << info.binning_y
        << "): the far stage decimates the calibrated image";
  } else if (info.roi.width != 0 && (info.roi.width != info.width || info.roi.height != info.height)) {
    why << "camera_info has a region of interest; the far stage needs the full calibrated image";
  } else if (!info.distortion_model.empty() && info.distortion_model != "plumb_bob" &&
             info.distortion_model != "rational_polynomial") {
    why << "distortion model '" << info.distortion_model << "' is not plumb_bob or rational_polynomial";
  }
  if (!why.str().empty()) {
    *problem = why.str();
    return std::nullopt;
  }
  PinholeCalibration calibration;
  calibration.size = cv::Size(static_cast<int>(info.width), static_cast<int>(info.height));
  for (int i = 0; i < 9; ++i) {
    calibration.camera_matrix(i / 3, i % 3) = info.K[static_cast<std::size_t>(i)];
    calibration.rectification(i / 3, i % 3) = info.R[static_cast<std::size_t>(i)];
  }
  for (int i = 0; i < 12; ++i) calibration.projection(i / 4, i % 4) = info.P[static_cast<std::size_t>(i)];
  calibration.distortion = info.D;
  return calibration;
}

// Everything calibrationOf() reads or checks: a camera_info that changes only its binning or region of
// interest must be checked again, not rectified with the cached maps.
bool sameCalibration(const sensor_msgs::CameraInfo& a, const sensor_msgs::CameraInfo& b) {
  return a.width == b.width && a.height == b.height && a.K == b.K && a.D == b.D && a.R == b.R && a.P == b.P &&
         a.distortion_model == b.distortion_model && a.binning_x == b.binning_x && a.binning_y == b.binning_y &&
         a.roi.x_offset == b.roi.x_offset && a.roi.y_offset == b.roi.y_offset && a.roi.width == b.roi.width &&
         a.roi.height == b.roi.height;
}

// The rectified camera as sensor_msgs/CameraInfo states it (see the file comment); with a window, the
// window's region of interest.
sensor_msgs::CameraInfo rectifiedInfo(const sensor_msgs::CameraInfo& raw, const std::optional<cv::Rect>& window) {
  sensor_msgs::CameraInfo out;
  out.header = raw.header;
  out.width = raw.width;
  out.height = raw.height;
  out.distortion_model = "plumb_bob";
  out.D.assign(5, 0.0);
  out.R = {1.0, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 1.0};
  out.P = raw.P;
  for (int row = 0; row < 3; ++row) {
    for (int col = 0; col < 3; ++col) out.K[static_cast<std::size_t>(row * 3 + col)] = raw.P[static_cast<std::size_t>(row * 4 + col)];
  }
  out.binning_x = 1;
  out.binning_y = 1;
  if (window) {
    out.roi.x_offset = static_cast<std::uint32_t>(window->x);
    out.roi.y_offset = static_cast<std::uint32_t>(window->y);
    out.roi.width = static_cast<std::uint32_t>(window->width);
    out.roi.height = static_cast<std::uint32_t>(window->height);
  }
  return out;
}

// No fused estimate this long (the arbiter stalled or gone): the whole image.
constexpr double kMaxFusedAgeS = 0.5;

}  // namespace

class FarStereoRectifyNodelet : public nodelet::Nodelet {
 public:
  void onInit() override;

 private:
  // One camera: its rectifier for the calibration it was built from, its outputs.
  struct Side {
    std::unique_ptr<WindowRectifier> rectifier;
    sensor_msgs::CameraInfo calibration_info;  // what `rectifier` was built from
    ros::Publisher image_publisher, info_publisher;
  };
  // The arbiter's last fused estimate, for the tracking window.
  struct FusedPort {
    bool usable = false;            // valid with a position
    double arrival_s = 0.0;         // ROS time
    ros::Time stamp;                // of the image it came from
    std::string frame_id;
    Eigen::Vector3d position_m = Eigen::Vector3d::Zero();
    Eigen::Vector3d velocity_mps = Eigen::Vector3d::Zero();
  };
  using Sync = message_filters::TimeSynchronizer<sensor_msgs::Image, sensor_msgs::CameraInfo, sensor_msgs::Image,
                                                 sensor_msgs::CameraInfo>;

  // The declared settings with the private namespace's values (config/far_stereo.yaml), and the matcher's
  // reach (~matcher: config/stereo_image_proc.yaml). Throws docking_settings::ConfigError naming the key.
  void readParameters();
  // The window to rectify for a pair at `stamp` in `frame_id`, or none (the whole image).
  std::optional<cv::Rect> windowFor(const ros::Time& stamp, const std::string& frame_id, const Side& side) const;
  void advertise(Side* side, const char* image, const char* info);
  int subscribers() const;
  void onConnection();
  void onFusedEstimate(const docking_msgs::TargetEstimateConstPtr& fused);
  void onPair(const sensor_msgs::ImageConstPtr& left, const sensor_msgs::CameraInfoConstPtr& left_info,
              const sensor_msgs::ImageConstPtr& right, const sensor_msgs::CameraInfoConstPtr& right_info);
  // The rectified image of one side, or nullptr and the problem that stops the pair.
  sensor_msgs::ImagePtr rectifySide(const char* name, const sensor_msgs::Image& image,
                                    const sensor_msgs::CameraInfo& info, Side* side,
                                    const std::optional<cv::Rect>& window, std::string* problem);
  void diagnose(diagnostic_updater::DiagnosticStatusWrapper& status);

  Side left_, right_;
  TrackingWindowParams window_params_;  // window_params_.enabled: windows while tracking
  MatcherReach matcher_reach_;
  ros::NodeHandle nh_;
  message_filters::Subscriber<sensor_msgs::Image> left_image_sub_, right_image_sub_;
  message_filters::Subscriber<sensor_msgs::CameraInfo> left_info_sub_, right_info_sub_;
  std::unique_ptr<Sync> sync_;
  ros::Subscriber fused_subscriber_;
  std::unique_ptr<diagnostic_updater::Updater> diagnostics_;
  ros::Timer diagnostics_timer_;

  std::mutex mutex_;  // everything below: the pair callback, the fused estimate, diagnostics, connections
  bool subscribed_{false};
  std::uint64_t pairs_{0};
  std::uint64_t windowed_pairs_{0};
  std::uint64_t dropped_{0};
  std::uint64_t dropped_at_last_report_{0};  // WARN only while pairs are being dropped, OK once they pass
  std::string last_problem_;
  FusedPort fused_port_;
  std::optional<cv::Rect> last_window_;  // for diagnostics
};

void FarStereoRectifyNodelet::readParameters() {
  ros::NodeHandle& pnh = getPrivateNodeHandle();
  try {
    FarStereoSettings settings;
    docking_settings::loadSettings(pnh, settings);
    docking_settings::warnUnknownKeys(pnh, settings, {"matcher"});
    // What the tracking window leaves room for: the full-resolution matcher's own settings.
    const docking_settings::ParamReader matcher(ros::NodeHandle(pnh, "matcher"));
    matcher_reach_.min_disparity = matcher.require<int>("min_disparity");
    matcher_reach_.disparity_range = matcher.require<int>("disparity_range");
    matcher_reach_.correlation_window_px = matcher.require<int>("correlation_window_size");
    const auto reach_problems = validateMatcherReach(matcher_reach_);
    if (!reach_problems.empty()) matcher.invalid("correlation_window_size", reach_problems.front());
    window_params_ = settings.window;
  } catch (const std::exception& error) {
    // The nodelet loader refuses this nodelet (and logs the message at DEBUG only): said here first.
    NODELET_FATAL("far_stereo_rectify: %s", error.what());
    throw;
  }
}

void FarStereoRectifyNodelet::advertise(Side* side, const char* image, const char* info) {
  const auto connection = [this](const ros::SingleSubscriberPublisher&) { onConnection(); };
  side->image_publisher = nh_.advertise<sensor_msgs::Image>(image, 1, connection, connection);
  side->info_publisher = nh_.advertise<sensor_msgs::CameraInfo>(info, 1, connection, connection);
}

void FarStereoRectifyNodelet::onInit() {
  nh_ = getNodeHandle();
  readParameters();
  namespace topics = docking_msgs::topics;
  advertise(&left_, topics::kStereoFarFullLeftImageRect, topics::kStereoFarFullLeftCameraInfo);
  advertise(&right_, topics::kStereoFarFullRightImageRect, topics::kStereoFarFullRightCameraInfo);
  sync_ = std::make_unique<Sync>(left_image_sub_, left_info_sub_, right_image_sub_, right_info_sub_, kSyncQueue);
  sync_->registerCallback(&FarStereoRectifyNodelet::onPair, this);
  if (window_params_.enabled) {
    fused_subscriber_ = nh_.subscribe(topics::kTargetEstimate, 1, &FarStereoRectifyNodelet::onFusedEstimate, this,
                                      ros::TransportHints().tcpNoDelay());
  }
  diagnostics_ = std::make_unique<diagnostic_updater::Updater>(nh_, getPrivateNodeHandle(), getName());
  diagnostics_->setHardwareID("far_stereo_rectify");
  diagnostics_->add("far stereo rectify", this, &FarStereoRectifyNodelet::diagnose);
  diagnostics_timer_ = nh_.createTimer(ros::Duration(1.0), [this](const ros::TimerEvent&) { diagnostics_->update(); });
  NODELET_INFO("far_stereo_rectify: full resolution%s; lazy",
               window_params_.enabled ? ", a window around the tracked target" : "");
}

int FarStereoRectifyNodelet::subscribers() const {
  return static_cast<int>(left_.image_publisher.getNumSubscribers() + left_.info_publisher.getNumSubscribers() +
                          right_.image_publisher.getNumSubscribers() + right_.info_publisher.getNumSubscribers());
}

void FarStereoRectifyNodelet::onConnection() {
  std::lock_guard<std::mutex> lock(mutex_);
  const bool wanted = subscribers() > 0;
  if (wanted == subscribed_) return;
  namespace topics = docking_msgs::topics;
  if (wanted) {
    left_image_sub_.subscribe(nh_, topics::kStereoLeftImageMono, 1);
    left_info_sub_.subscribe(nh_, topics::kStereoLeftCameraInfoChecked, 1);
    right_image_sub_.subscribe(nh_, topics::kStereoRightImageMono, 1);
    right_info_sub_.subscribe(nh_, topics::kStereoRightCameraInfoChecked, 1);
  } else {
    left_image_sub_.unsubscribe();
    left_info_sub_.unsubscribe();
    right_image_sub_.unsubscribe();
    right_info_sub_.unsubscribe();
  }
  subscribed_ = wanted;
}

void FarStereoRectifyNodelet::onFusedEstimate(const docking_msgs::TargetEstimateConstPtr& fused) {
  std::lock_guard<std::mutex> lock(mutex_);
  // Any source: the disparity track itself or a monocular pose both say where the target is.
  const double now_s = ros::Time::now().toSec();
  fused_port_.usable = fused->valid && fused->position_valid;
  fused_port_.arrival_s = now_s;
  fused_port_.stamp = fused->header.stamp;
  fused_port_.frame_id = fused->header.frame_id;
  const auto& p = fused->pose.pose.position;
  fused_port_.position_m = Eigen::Vector3d(p.x, p.y, p.z);
  const auto& v = fused->twist.twist.linear;
  fused_port_.velocity_mps = fused->twist_valid ? Eigen::Vector3d(v.x, v.y, v.z) : Eigen::Vector3d::Zero();
}

std::optional<cv::Rect> FarStereoRectifyNodelet::windowFor(const ros::Time& stamp, const std::string& frame_id,
                                                           const Side& side) const {
  // Only a fresh, valid estimate in the left camera's own frame (the arbiter's output_frame) places it;
  // anything else, and the port predicted out of view, is matched on the whole image.
  if (!window_params_.enabled || !fused_port_.usable || !side.rectifier || fused_port_.frame_id != frame_id ||
      ros::Time::now().toSec() - fused_port_.arrival_s > kMaxFusedAgeS) {
    return std::nullopt;
  }
  const Eigen::Vector3d port =
      predictPort(fused_port_.position_m, fused_port_.velocity_mps, (stamp - fused_port_.stamp).toSec());
  return trackingWindow(side.rectifier->outputProjection(), port, side.rectifier->outputSize(), matcher_reach_,
                        window_params_);
}

sensor_msgs::ImagePtr FarStereoRectifyNodelet::rectifySide(const char* name, const sensor_msgs::Image& image,
                                                           const sensor_msgs::CameraInfo& info, Side* side,
                                                           const std::optional<cv::Rect>& window,
                                                           std::string* problem) {
  std::ostringstream why;
  if (image.encoding != sensor_msgs::image_encodings::MONO8) {
    why << name << " image encoding must be mono8 (image_mono), got '" << image.encoding << "'";
  } else if (image.width != info.width || image.height != info.height) {
    why << name << " image " << image.width << "x" << image.height << " differs from its camera_info's "
        << info.width << "x" << info.height;
  } else if (image.step < image.width || image.data.size() < static_cast<std::size_t>(image.step) * image.height) {
    why << name << " image data too short for " << image.width << "x" << image.height;
  }
  if (!why.str().empty()) {
    *problem = why.str();
    return nullptr;
  }
  if (!side->rectifier || !sameCalibration(side->calibration_info, info)) {
    std::string calibration_problem;
    const auto calibration = calibrationOf(info, &calibration_problem);
    const auto reasons = calibration ? validateCalibration(*calibration) : std::vector<std::string>{};
    if (!calibration || !reasons.empty()) {
      *problem = std::string(name) + " camera_info: " + (calibration ? reasons.front() : calibration_problem);
      side->rectifier.reset();
      return nullptr;
    }
    side->rectifier = std::make_unique<WindowRectifier>(*calibration);
    side->calibration_info = info;
  }
  const cv::Mat grey(static_cast<int>(image.height), static_cast<int>(image.width), CV_8UC1,
                     const_cast<std::uint8_t*>(image.data.data()), image.step);
  cv::Mat rectified;
  if (window) {
    side->rectifier->rectifyWindow(grey, *window, &rectified);
  } else {
    side->rectifier->rectify(grey, &rectified);
  }
  auto out = boost::make_shared<sensor_msgs::Image>();
  out->header = image.header;
  out->encoding = sensor_msgs::image_encodings::MONO8;
  out->width = static_cast<std::uint32_t>(rectified.cols);
  out->height = static_cast<std::uint32_t>(rectified.rows);
  out->step = out->width;
  out->data.assign(rectified.data, rectified.data + rectified.total());
  return out;
}

void FarStereoRectifyNodelet::onPair(const sensor_msgs::ImageConstPtr& left,
                                     const sensor_msgs::CameraInfoConstPtr& left_info,
                                     const sensor_msgs::ImageConstPtr& right,
                                     const sensor_msgs::CameraInfoConstPtr& right_info) {
  std::lock_guard<std::mutex> lock(mutex_);
  std::string problem;
  sensor_msgs::ImagePtr left_rect, right_rect;
  // The window from the left side's rectifier as last built: a calibration change rebuilds it below, and the
  // window of the old one is still inside the image (same size checked there).
  const std::optional<cv::Rect> window = windowFor(left->header.stamp, left->header.frame_id, left_);
  try {
    left_rect = rectifySide("left", *left, *left_info, &left_, window, &problem);
    if (left_rect) right_rect = rectifySide("right", *right, *right_info, &right_, window, &problem);
  } catch (const std::exception& e) {
    problem = std::string("rectification failed: ") + e.what();
  }
  if (!left_rect || !right_rect) {
    NODELET_ERROR_THROTTLE(5.0, "far_stereo_rectify: pair at %.3f dropped: %s", left->header.stamp.toSec(),
                           problem.c_str());
    ++dropped_;
    last_problem_ = problem;
    return;
  }
  // camera_info first: the detector matches a window's disparity to its camera_info by stamp.
  left_.info_publisher.publish(rectifiedInfo(*left_info, window));
  right_.info_publisher.publish(rectifiedInfo(*right_info, window));
  left_.image_publisher.publish(left_rect);
  right_.image_publisher.publish(right_rect);
  ++pairs_;
  if (window) {
    ++windowed_pairs_;
    last_window_ = window;
  }
}

void FarStereoRectifyNodelet::diagnose(diagnostic_updater::DiagnosticStatusWrapper& status) {
  std::lock_guard<std::mutex> lock(mutex_);
  const bool dropping = dropped_ > dropped_at_last_report_;
  dropped_at_last_report_ = dropped_;
  if (!dropping) {
    status.summary(diagnostic_msgs::DiagnosticStatus::OK, !subscribed_ ? "idle (no subscriber)" : "rectifying");
  } else {
    status.summary(diagnostic_msgs::DiagnosticStatus::WARN, "pairs dropped: " + last_problem_);
  }
  status.add("pairs", pairs_);
  status.add("pairs dropped", dropped_);
  status.add("tracking window", window_params_.enabled ? "enabled" : "disabled");
  status.add("pairs in a tracking window", windowed_pairs_);
  std::ostringstream window;
  if (last_window_) {
    window << last_window_->width << "x" << last_window_->height << " at (" << last_window_->x << ", "
           << last_window_->y << ")";
  }
  status.add("last tracking window", last_window_ ? window.str() : std::string("(none)"));
  status.add("last drop reason", last_problem_.empty() ? "(none)" : last_problem_);
  status.add("subscribed", subscribed_);
}

}  // namespace disparity
}  // namespace docking_perception

PLUGINLIB_EXPORT_CLASS(docking_perception::disparity::FarStereoRectifyNodelet, nodelet::Nodelet)
