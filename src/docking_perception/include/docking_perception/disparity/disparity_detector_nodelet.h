// disparity_detector nodelet: the thin ROS wrapper around DisparityDetector (see the package README).
//
// Subscribes (lazily, only while an output has subscribers and the stage is not paused):
//   stereo/disparity           stereo_msgs/DisparityImage (stereo_image_proc)
//   stereo/far/full/left/camera_info  sensor_msgs/CameraInfo: the rectified principal point (a tracking
//                              window's: where the window lies)
//   stereo/far/full/left/image_rect  sensor_msgs/Image mono8: the left image each disparity was computed
//                              from, matched by stamp and size, for the appearance check (face_appearance.h)
// and always
//   target/estimate            docking_msgs/TargetEstimate, the arbiter's: near and monocular pauses the
//                              stage (duty/fused_range_condition.h)
// Publishes:
//   perception/disparity/estimate     docking_msgs/TargetEstimate (SOURCE_DISPARITY, position only)
//   perception/disparity/debug_image  sensor_msgs/Image bgr8 (image_transport)
//   /diagnostics                      detection rate, frames per deciding stage and code, last rejection
// Settings: settings/disparity_detector.yaml declares them (defaults, ranges, meaning); config/disparity_detector.yaml
// holds what differs from the defaults. All are live through dynamic_reconfigure. ~target_yaml: the mockup and
// its port's height; ~robot_yaml: the cameras' height (config/robot.yaml); ~matcher/correlation_window_size: the
// block matcher's window (config/stereo_image_proc.yaml), its blind band and the shape check's pixel tolerance.
#pragma once

#include <deque>
#include <memory>
#include <map>
#include <mutex>
#include <string>
#include <utility>

#include <diagnostic_updater/diagnostic_updater.h>
#include <docking_msgs/TargetEstimate.h>
#include <docking_msgs/latency_window.h>
#include <dynamic_reconfigure/server.h>
#include <image_transport/image_transport.h>
#include <nodelet/nodelet.h>
#include <ros/ros.h>
#include <sensor_msgs/CameraInfo.h>
#include <sensor_msgs/Image.h>
#include <stereo_msgs/DisparityImage.h>

#include "docking_perception/DisparityDetectorConfig.h"
#include "docking_perception/disparity/disparity_detector.h"
#include "docking_perception/disparity/face_appearance.h"
#include "docking_perception/disparity/stages.h"
#include "docking_perception/duty/fused_range_condition.h"
#include "docking_perception/disparity/target_track_gate.h"

namespace docking_perception {

class DisparityDetectorNodelet : public nodelet::Nodelet {
 public:
  DisparityDetectorNodelet() = default;
  ~DisparityDetectorNodelet() override = default;

 private:
  using Config = docking_perception::DisparityDetectorConfig;

  void onInit() override;
  void advertise();

  // The declared defaults with the private namespace's values; the mockup of ~target_yaml (its size and its
  // face print) and the rig of ~robot_yaml. Throws docking_settings::ConfigError naming the key.
  disparity::DisparityDetectorSettings loadSettings();
  static duty::FusedRangeConditionParams toPauseParams(const disparity::PauseParams& pause);
  void onReconfigure(Config& config, uint32_t level);

  // Subscribes to the inputs while any output has a subscriber and the stage is not paused,
  // unsubscribes otherwise.
  void updateSubscriptions();
  void onFusedEstimate(const docking_msgs::TargetEstimateConstPtr& fused);
  void onCameraInfo(const sensor_msgs::CameraInfoConstPtr& info);
  void onLeftImage(const sensor_msgs::ImageConstPtr& image);
  // What a disparity image is read with: the settings and detector in force, its camera model (a window's or
  // the whole image's), the region the matcher searched, the tracked target's hint.
  struct Frame {
    disparity::DisparityDetectorSettings settings;
    disparity::DisparityDetector detector;
    disparity::StereoGeometry geometry;
    disparity::ImageWindow window;
    cv::Rect valid_region;
    disparity::SearchHint hint;
  };
  // The frame of `message`; false (and why) when a window's disparity has no camera_info (stage 1).
  bool prepareFrame(const stereo_msgs::DisparityImage& message, Frame* frame, std::string* problem);
  bool cameraModel(const stereo_msgs::DisparityImage& message, const sensor_msgs::CameraInfoConstPtr& camera_info,
                   bool windows_recently, Frame* frame, std::string* problem);
  // Stage 6: the appearance check on a found detection (face_appearance.h), with the left image of the
  // disparity's stamp and size; without one the detection is kept and counted (diagnostics).
  void confirmAppearance(const stereo_msgs::DisparityImage& message, const cv::Mat& disparity,
                         const disparity::DetectorParams& params,
                         const disparity::StereoGeometry& geometry, disparity::Detection* detection);
  // Catches what processDisparity throws: the message is reported as invalid input, the node goes on.
  void onDisparity(const stereo_msgs::DisparityImageConstPtr& message);
  void processDisparity(const stereo_msgs::DisparityImageConstPtr& message);
  // Publishes valid = false with `status` (bad input, stage 1: `outcome`), and counts it in the diagnostics.
  void publishInvalidInput(const stereo_msgs::DisparityImage& message, disparity::StageOutcome outcome,
                           const std::string& status, double cpu_start_ms);
  void publishDebugImage(const stereo_msgs::DisparityImage& message, const cv::Mat& disparity,
                         const disparity::Detection& detection, double display_max_px);
  void applyTrackGate(double stamp_s, disparity::Detection* detection);
  void checkOutput(disparity::Detection* detection, docking_msgs::TargetEstimate* estimate);
  void produceDiagnostics(diagnostic_updater::DiagnosticStatusWrapper& status);
  void summarize(diagnostic_updater::DiagnosticStatusWrapper& status, bool paused, double rate) const;
  void recordOutcome(disparity::StageOutcome outcome, bool found, const std::string& reason, double processing_ms);
  // Publishes and records the image stamp -> publication latency (takes state_mutex_).
  void publishEstimate(const docking_msgs::TargetEstimate& estimate);
  void recordDebugImage(double cpu_ms);

  ros::NodeHandle nh_;
  ros::NodeHandle private_nh_;
  std::unique_ptr<image_transport::ImageTransport> image_transport_;
  ros::Publisher estimate_publisher_;
  image_transport::Publisher debug_publisher_;
  ros::Subscriber disparity_subscriber_;
  // The far stage's left camera_info (far_stereo_rectify).
  ros::Subscriber camera_info_subscriber_;
  // ...and its left rectified images (the appearance check).
  ros::Subscriber left_image_subscriber_;
  std::mutex connection_mutex_;

  // Resting near the target (issue 15): the arbiter's output, and a timer that resumes the stage when
  // that output stops arriving.
  static constexpr double kPauseCheckPeriodS = 0.1;
  // Resumed once the fused estimate is this far beyond the pause range, so the range's noise does not toggle
  // the stage.
  static constexpr double kPauseHysteresisM = 0.1;
  // Resumed when no fused estimate arrived for this long (the arbiter stalled or gone).
  static constexpr double kPauseMaxFusedAgeS = 0.3;
  ros::Subscriber fused_subscriber_;
  ros::Timer pause_timer_;
  std::mutex pause_mutex_;
  duty::FusedRangeCondition near_{duty::RangeSide::kInside};  // target inside pause_inside_range_m on mono
  duty::FusedRangeState near_state_ = duty::FusedRangeState::kNoFusedEstimate;  // as last applied

  boost::recursive_mutex reconfigure_mutex_;
  std::unique_ptr<dynamic_reconfigure::Server<Config>> reconfigure_server_;

  std::unique_ptr<diagnostic_updater::Updater> diagnostics_;
  ros::Timer diagnostics_timer_;

  // State shared by the callbacks.
  std::mutex state_mutex_;
  disparity::DisparityDetectorSettings settings_;
  disparity::DisparityDetector detector_;  // with the mockup of ~target_yaml, read once at start-up
  disparity::TargetTrackGate track_gate_;
  sensor_msgs::CameraInfoConstPtr camera_info_;  // the far stage's last left camera_info of the whole image
  // The far stage's tracking windows (camera_info with a region of interest): the last few, matched to a
  // disparity image by stamp; a window disparity without its own is dropped, never read with another's.
  static constexpr std::size_t kRecentWindowInfos = 8;
  static constexpr double kWindowInfoMemoryS = 2.0;  // windows seen this recently: unmatched ones are dropped
  std::deque<sensor_msgs::CameraInfoConstPtr> recent_window_infos_;
  // The far stage's last left images, matched to a disparity image by stamp and size.
  static constexpr std::size_t kRecentLeftImages = 8;
  std::deque<sensor_msgs::ImageConstPtr> recent_left_images_;
  int blind_band_extra_px_ = 0;  // half the matcher's correlation window, rounded up (read at start-up)
  std::unique_ptr<disparity::FaceAppearanceCheck> appearance_check_;  // the print of ~target_yaml, read at start-up
  unsigned long appearance_rejections_ = 0;   // found blobs whose face did not show the print
  unsigned long appearance_unjudged_ = 0;     // ...whose face could not be judged (glare, dark, outside)
  unsigned long appearance_without_image_ = 0;  // ...checked without a left image of their stamp
  std::string last_appearance_;               // the last check's reason
  double last_window_info_arrival_s_ = 0.0;  // of the last of recent_window_infos_
  unsigned long window_frames_ = 0;
  bool warned_no_camera_info_ = false;
  // The diagnostics' detection rate is over this many frames (4 s at 7.5 Hz).
  static constexpr std::size_t kDiagnosticWindowFrames = 30;
  std::deque<bool> recent_found_;  // detection outcome of the last kDiagnosticWindowFrames frames
  std::map<std::pair<disparity::Stage, std::uint8_t>, unsigned long> outcome_counts_;  // frames per deciding stage
  std::string last_rejection_;
  std::string last_input_error_;
  unsigned long frames_ = 0;
  unsigned long detections_ = 0;
  double last_processing_ms_ = 0.0;
  double last_range_m_ = 0.0;
  docking_msgs::LatencyWindow latency_;  // image stamp -> estimate published
  // Debug images are drawn only while someone subscribes: what they cost, and proof of none without.
  unsigned long debug_images_ = 0;
  double debug_image_cpu_ms_total_ = 0.0;
};

}  // namespace docking_perception
