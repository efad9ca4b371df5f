// image_guard: one camera's image_raw and camera_info checked before image_proc sees them (issue 12,
// item 1). Subscribes
// `image_raw` through image_transport (~image_transport: raw, or the compressed plugin of
// docking_image_transport, as the debayer nodelets did), republishes every valid image unchanged on
// `image_checked` (the same shared pointer: no copy in the manager) and drops a malformed one with a
// throttled warning and a diagnostic naming its publisher (raw transport: the MessageEvent's publisher;
// another transport: its topic) and the problem (image_check.h). Likewise `camera_info` ->
// `camera_info_checked`: a camera_info passes when it is well formed and describes the size of this
// camera's last image that passed (image_proc's rectify, stereo_image_proc and our estimators read it).
// Settings: settings/image_guard.yaml (max_rate_hz: valid frames passed at most this often, by stamp, image
// and camera_info alike: rate_cap.h; near_*: a lower cap while the arbiter's target/estimate is a monocular
// pose inside near_range_m: block matching at a keep-alive rate near; duty/fused_range_condition.h).
#include <docking_settings/ros_loader.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <map>
#include <memory>
#include <mutex>
#include <optional>
#include <stdexcept>
#include <string>

#include <diagnostic_updater/diagnostic_updater.h>
#include <image_transport/image_transport.h>
#include <nodelet/nodelet.h>
#include <pluginlib/class_list_macros.hpp>
#include <ros/ros.h>
#include <sensor_msgs/CameraInfo.h>
#include <sensor_msgs/Image.h>

#include "docking_msgs/TargetEstimate.h"
#include "docking_msgs/names.h"
#include "docking_perception/duty/fused_range_condition.h"
#include "docking_perception/image_guard/image_check.h"
#include "docking_perception/image_guard/rate_cap.h"

namespace docking_perception {
namespace image_guard {

class ImageGuardNodelet : public nodelet::Nodelet {
 public:
  void onInit() override;

 private:
  void readParameters();
  void onImage(const sensor_msgs::ImageConstPtr& image, const std::string& publisher);
  void onCameraInfo(const ros::MessageEvent<sensor_msgs::CameraInfo const>& event);
  void checkAndPassCameraInfo(const sensor_msgs::CameraInfoConstPtr& info, const std::string& publisher);
  void diagnose(diagnostic_updater::DiagnosticStatusWrapper& status);
  void onFusedEstimate(const docking_msgs::TargetEstimateConstPtr& fused);
  /// Whether the lower cap applies to a frame arriving now (near_max_rate_hz set, the condition holds).
  bool nearCapInForce() const;  // under mutex_
  /// The cap for a frame arriving now: near_max_rate_hz while the near condition holds, else max_rate_hz.
  double maxRateHzFor(bool near_cap) const;

  ImageLimits limits_;
  RateCap rate_cap_;  // the cap in force; under mutex_
  double max_rate_hz_{0.0};       // ~max_rate_hz
  double near_max_rate_hz_{0.0};  // ~near_max_rate_hz (0: no lower cap near)
  duty::FusedRangeCondition near_{duty::RangeSide::kInside};  // under mutex_
  ros::Subscriber fused_subscriber_;
  std::unique_ptr<image_transport::ImageTransport> image_transport_;
  // raw: a plain subscriber, whose MessageEvent names the publisher; other transports (compressed):
  // image_transport, whose callback does not, so the drops name the transport topic instead.
  ros::Subscriber raw_subscriber_;
  image_transport::Subscriber transport_subscriber_;
  std::string input_topic_;
  ros::Publisher checked_publisher_;
  ros::Subscriber info_subscriber_;
  ros::Publisher info_checked_publisher_;
  std::unique_ptr<diagnostic_updater::Updater> diagnostics_;
  ros::Timer diagnostics_timer_;

  std::mutex mutex_;  // guards the counts below (image callback and diagnostics timer)
  std::uint64_t passed_{0};
  std::uint64_t passed_at_full_rate_{0};  // passed while the lower cap near was not in force
  std::uint64_t images_capped_{0};  // valid, left out by ~max_rate_hz (not faults)
  std::uint64_t infos_capped_{0};
  std::array<std::uint64_t, kImageProblemCount> dropped_{};
  std::string last_drop_;  ///< publisher, code and details of the last dropped image
  std::optional<ImageSize> last_image_size_;  ///< of the last image that passed
  /// The latest camera_info that came before any image (a camera may publish a frame's info first), and
  /// its publisher: checked and passed with the first image, so that the first frame is not lost.
  sensor_msgs::CameraInfoConstPtr info_before_first_image_;
  std::string info_before_first_image_publisher_;
  std::uint64_t infos_passed_{0};
  std::array<std::uint64_t, kCameraInfoProblemCount> infos_dropped_{};
  std::string last_info_drop_;
};

void ImageGuardNodelet::readParameters() {
  const ros::NodeHandle& pnh = getPrivateNodeHandle();
  ImageGuardSettings settings;
  docking_settings::loadSettings(pnh, settings);
  docking_settings::warnUnknownKeys(pnh, settings);
  limits_ = settings.limits;
  max_rate_hz_ = settings.max_rate_hz;
  near_max_rate_hz_ = settings.near_max_rate_hz;
  duty::FusedRangeConditionParams near;
  near.range_m = near_max_rate_hz_ > 0.0 ? settings.near_range_m : 0.0;  // the condition is off with its rate
  near.hysteresis_m = settings.near_hysteresis_m;
  near.max_fused_age_s = settings.near_max_fused_age_s;
  near_.setParams(near);
  rate_cap_ = RateCap(max_rate_hz_);
}

void ImageGuardNodelet::onInit() {
  // A bad parameter throws out of onInit: the loader refuses this nodelet (perception_host says so; a
  // `nodelet load` exits non-zero) and carries on; nothing is subscribed or advertised yet. Said here first: Debian's
  // nodelet::Loader logs the exception's message at DEBUG only.
  try {
    readParameters();
  } catch (const std::exception& e) {
    NODELET_FATAL("image_guard: %s: not starting", e.what());
    throw;
  }
  ros::NodeHandle& nh = getNodeHandle();
  ros::NodeHandle& pnh = getPrivateNodeHandle();
  image_transport_ = std::make_unique<image_transport::ImageTransport>(nh);
  checked_publisher_ = nh.advertise<sensor_msgs::Image>("image_checked", 2);
  info_checked_publisher_ = nh.advertise<sensor_msgs::CameraInfo>("camera_info_checked", 2);
  diagnostics_ = std::make_unique<diagnostic_updater::Updater>(nh, pnh, getName());
  diagnostics_->setHardwareID(nh.resolveName("image_raw"));
  diagnostics_->add("image guard " + nh.resolveName("image_raw"), this, &ImageGuardNodelet::diagnose);
  diagnostics_timer_ = nh.createTimer(ros::Duration(1.0), [this](const ros::TimerEvent&) { diagnostics_->update(); });
  if (near_.params().range_m > 0.0) {
    fused_subscriber_ = nh.subscribe(docking_msgs::topics::kTargetEstimate, 1, &ImageGuardNodelet::onFusedEstimate, this,
                                     ros::TransportHints().tcpNoDelay());  // small and timely: no Nagle delay
  }
  // ~image_transport chooses the transport (default raw), as image_proc's nodelets read it.
  const image_transport::TransportHints hints("raw", ros::TransportHints(), pnh);
  if (hints.getTransport() == "raw") {
    // A boost::function of the event type: a lambda given to subscribe<M>() is wrapped as a callback of
    // the message pointer, and the event built from that pointer names no publisher.
    const boost::function<void(const ros::MessageEvent<sensor_msgs::Image const>&)> callback =
        [this](const ros::MessageEvent<sensor_msgs::Image const>& event) {
          onImage(event.getConstMessage(), event.getPublisherName());
        };
    raw_subscriber_ = nh.subscribe<sensor_msgs::Image>("image_raw", 2, callback);
    input_topic_ = raw_subscriber_.getTopic();
  } else {
    transport_subscriber_ = image_transport_->subscribe(
        "image_raw", 2,
        [this](const sensor_msgs::ImageConstPtr& image) {
          onImage(image, "(a publisher of " + transport_subscriber_.getTopic() + ", " +
                             transport_subscriber_.getTransport() + " transport)");
        },
        ros::VoidPtr(), hints);
    input_topic_ = transport_subscriber_.getTopic() + " (" + transport_subscriber_.getTransport() + ")";
  }
  const boost::function<void(const ros::MessageEvent<sensor_msgs::CameraInfo const>&)> info_callback =
      [this](const ros::MessageEvent<sensor_msgs::CameraInfo const>& event) { onCameraInfo(event); };
  info_subscriber_ = nh.subscribe<sensor_msgs::CameraInfo>("camera_info", 2, info_callback);
  NODELET_INFO("image_guard: %s -> %s, %s -> %s", input_topic_.c_str(), checked_publisher_.getTopic().c_str(),
               info_subscriber_.getTopic().c_str(), info_checked_publisher_.getTopic().c_str());
}

void ImageGuardNodelet::onImage(const sensor_msgs::ImageConstPtr& image, const std::string& publisher) {
  ImageProblem problem = ImageProblem::kNone;
  try {
    ImageFacts facts;
    facts.encoding = image->encoding;
    facts.width = image->width;
    facts.height = image->height;
    facts.step = image->step;
    facts.data_size = image->data.size();
    facts.is_bigendian = image->is_bigendian;
    facts.frame_id = image->header.frame_id;
    facts.stamp_s = image->header.stamp.toSec();
    problem = checkImage(facts, ros::Time::now().toSec(), limits_);
    if (problem == ImageProblem::kNone) {
      sensor_msgs::CameraInfoConstPtr held_info;
      std::string held_info_publisher;
      {
        // Before the publish: the camera_info of this image may be checked while image_proc works on it.
        std::lock_guard<std::mutex> lock(mutex_);
        const bool near_cap = nearCapInForce();
        rate_cap_.setMaxRateHz(maxRateHzFor(near_cap));
        if (!rate_cap_.admit(facts.stamp_s)) {
          ++images_capped_;
          return;
        }
        ++passed_;
        if (!near_cap) ++passed_at_full_rate_;
        last_image_size_ = ImageSize{image->width, image->height};
        held_info.swap(info_before_first_image_);
        held_info_publisher.swap(info_before_first_image_publisher_);
      }
      checked_publisher_.publish(image);  // the same pointer: intra-process subscribers get it uncopied
      if (held_info) checkAndPassCameraInfo(held_info, held_info_publisher);
      return;
    }
  } catch (const std::exception& e) {  // a publish on a shut-down publisher, bad_alloc: drop, go on
    NODELET_ERROR_THROTTLE(5.0, "image_guard: %s", e.what());
    return;
  }
  const std::string details = std::string(imageProblemName(problem)) + ": '" + image->encoding + "' " +
                              std::to_string(image->width) + "x" + std::to_string(image->height) + ", step " +
                              std::to_string(image->step) + ", " + std::to_string(image->data.size()) +
                              " bytes, frame '" + image->header.frame_id + "'";
  NODELET_WARN_THROTTLE(2.0, "image_guard: dropped an image on %s from %s: %s", input_topic_.c_str(),
                        publisher.c_str(), details.c_str());
  std::lock_guard<std::mutex> lock(mutex_);
  ++dropped_[static_cast<std::size_t>(problem)];
  last_drop_ = "from " + publisher + ": " + details;
}

namespace {
CameraInfoFacts factsOf(const sensor_msgs::CameraInfo& info) {
  CameraInfoFacts f;
  f.width = info.width;
  f.height = info.height;
  f.binning_x = info.binning_x;
  f.binning_y = info.binning_y;
  f.roi_x_offset = info.roi.x_offset;
  f.roi_y_offset = info.roi.y_offset;
  f.roi_width = info.roi.width;
  f.roi_height = info.roi.height;
  f.distortion_model = info.distortion_model;
  f.D = info.D;
  std::copy(info.K.begin(), info.K.end(), f.K.begin());
  std::copy(info.R.begin(), info.R.end(), f.R.begin());
  std::copy(info.P.begin(), info.P.end(), f.P.begin());
  f.frame_id = info.header.frame_id;
  f.stamp_s = info.header.stamp.toSec();
  return f;
}
}  // namespace

void ImageGuardNodelet::onCameraInfo(const ros::MessageEvent<sensor_msgs::CameraInfo const>& event) {
  checkAndPassCameraInfo(event.getConstMessage(), event.getPublisherName());
}

void ImageGuardNodelet::checkAndPassCameraInfo(const sensor_msgs::CameraInfoConstPtr& info,
                                               const std::string& publisher) {
  CameraInfoProblem problem = CameraInfoProblem::kNone;
  try {
    std::optional<ImageSize> last_image;
    {
      std::lock_guard<std::mutex> lock(mutex_);
      if (!last_image_size_) {
        // Before any image (a camera may publish a frame's info first): start-up order, not a fault.
        // Held, and checked and passed by onImage with the first image (under this lock: no race).
        info_before_first_image_ = info;
        info_before_first_image_publisher_ = publisher;
        ++infos_dropped_[static_cast<std::size_t>(CameraInfoProblem::kNoImageYet)];
        return;
      }
      last_image = last_image_size_;
    }
    problem = checkCameraInfo(factsOf(*info), last_image, ros::Time::now().toSec(), limits_);
    if (problem == CameraInfoProblem::kNone) {
      {
        std::lock_guard<std::mutex> lock(mutex_);
        rate_cap_.setMaxRateHz(maxRateHzFor(nearCapInForce()));
        if (!rate_cap_.admit(info->header.stamp.toSec())) {
          ++infos_capped_;
          return;
        }
        ++infos_passed_;
      }
      info_checked_publisher_.publish(info);
      return;
    }
  } catch (const std::exception& e) {
    NODELET_ERROR_THROTTLE(5.0, "image_guard: %s", e.what());
    return;
  }
  const std::string details = std::string(cameraInfoProblemName(problem)) + ": " + std::to_string(info->width) +
                              "x" + std::to_string(info->height) + ", model '" + info->distortion_model + "', " +
                              std::to_string(info->D.size()) + " coefficients, frame '" + info->header.frame_id + "'";
  NODELET_WARN_THROTTLE(2.0, "image_guard: dropped a camera_info on %s from %s: %s",
                        info_subscriber_.getTopic().c_str(), publisher.c_str(), details.c_str());
  std::lock_guard<std::mutex> lock(mutex_);
  ++infos_dropped_[static_cast<std::size_t>(problem)];
  last_info_drop_ = "from " + publisher + ": " + details;
}

void ImageGuardNodelet::onFusedEstimate(const docking_msgs::TargetEstimateConstPtr& fused) {
  const bool monocular = fused->selected_source == docking_msgs::TargetEstimate::SOURCE_MONO_VISIBLE ||
                         fused->selected_source == docking_msgs::TargetEstimate::SOURCE_MONO_IR;
  std::lock_guard<std::mutex> lock(mutex_);
  near_.onFusedEstimate(ros::Time::now().toSec(), fused->valid && fused->position_valid, monocular, fused->range_m);
}

bool ImageGuardNodelet::nearCapInForce() const {
  return near_max_rate_hz_ > 0.0 && near_.holds(ros::Time::now().toSec());
}

double ImageGuardNodelet::maxRateHzFor(bool near_cap) const {
  if (!near_cap) return max_rate_hz_;
  return max_rate_hz_ > 0.0 ? std::min(max_rate_hz_, near_max_rate_hz_) : near_max_rate_hz_;
}

void ImageGuardNodelet::diagnose(diagnostic_updater::DiagnosticStatusWrapper& status) {
  std::lock_guard<std::mutex> lock(mutex_);
  std::uint64_t dropped = 0;
  for (std::uint64_t n : dropped_) dropped += n;
  std::uint64_t infos_dropped = 0;  // faults only: an info before the first image is start-up order
  for (std::size_t i = 1; i < kCameraInfoProblemCount; ++i) {
    if (static_cast<CameraInfoProblem>(i) != CameraInfoProblem::kNoImageYet) infos_dropped += infos_dropped_[i];
  }
  if (dropped == 0 && infos_dropped == 0) {
    status.summary(diagnostic_msgs::DiagnosticStatus::OK, "every image and camera_info passed");
  } else if (dropped > 0) {
    status.summaryf(diagnostic_msgs::DiagnosticStatus::WARN, "%llu image(s) dropped; last %s",
                    static_cast<unsigned long long>(dropped), last_drop_.c_str());
  } else {
    status.summaryf(diagnostic_msgs::DiagnosticStatus::WARN, "%llu camera_info(s) dropped; last %s",
                    static_cast<unsigned long long>(infos_dropped), last_info_drop_.c_str());
  }
  status.add("passed", passed_);
  status.add("max rate Hz (0: every frame)", max_rate_hz_);
  status.add("near: max rate Hz (0: off)", near_max_rate_hz_);
  status.add("near", duty::describe(near_.state(ros::Time::now().toSec())));
  status.add("rate cap in force Hz (0: every frame)", rate_cap_.maxRateHz());
  status.add("passed at the full rate", passed_at_full_rate_);
  status.add("left out by the rate cap", images_capped_);
  status.add("camera_info left out by the rate cap", infos_capped_);
  for (std::size_t i = 1; i < kImageProblemCount; ++i) {
    status.add(std::string("dropped: ") + imageProblemName(static_cast<ImageProblem>(i)), dropped_[i]);
  }
  if (!last_drop_.empty()) status.add("last dropped", last_drop_);
  status.add("camera_info passed", infos_passed_);
  for (std::size_t i = 1; i < kCameraInfoProblemCount; ++i) {
    status.add(std::string("camera_info dropped: ") + cameraInfoProblemName(static_cast<CameraInfoProblem>(i)),
               infos_dropped_[i]);
  }
  if (!last_info_drop_.empty()) status.add("last dropped camera_info", last_info_drop_);
}

}  // namespace image_guard
}  // namespace docking_perception

PLUGINLIB_EXPORT_CLASS(docking_perception::image_guard::ImageGuardNodelet, nodelet::Nodelet)
