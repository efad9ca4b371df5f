// The ROS side shared by the stereo and IR camera nodelets: read and validate parameters, run the capture
// rig (core library) in its own thread, publish image + camera_info pairs, report diagnostics.
#pragma once

#include <docking_perception/camera/camera_capture_settings.h>
#include <docking_perception/camera/capture_rig.h>
#include <docking_perception/camera/frame_format.h>

#include <camera_info_manager/camera_info_manager.h>
#include <docking_settings/param_reader.h>
#include <diagnostic_updater/diagnostic_updater.h>
#include <diagnostic_updater/update_functions.h>
#include <image_transport/image_transport.h>
#include <nodelet/nodelet.h>
#include <ros/ros.h>

#include <atomic>
#include <memory>
#include <string>
#include <thread>
#include <vector>

namespace docking_perception {

// What differs between the cameras: where their settings and topics are, and their defaults.
struct CameraChannelDefaults {
  std::string param_prefix;  // "left/", "right/", or "" (settings directly under ~)
  std::string image_topic;   // names.h constant, e.g. "stereo/left/image_raw"
  std::string camera_name;   // camera_info_manager name, e.g. "stereo_left"
  std::string frame_id;      // names.h optical frame
};

class CaptureNodelet : public nodelet::Nodelet {
 public:
  ~CaptureNodelet() override;

 protected:
  CaptureNodelet(std::vector<CameraChannelDefaults> channels, camera::ColourMode colour_mode);
  void onInit() override;

  /// The node's settings (settings/stereo_camera.yaml, settings/ir_camera.yaml): the capture and one
  /// ChannelSettings per channel, in the order of the channels given to the constructor.
  struct CameraSettings {
    camera::CaptureNodeSettings capture;
    std::vector<camera::ChannelSettings> channels;
  };
  virtual CameraSettings loadSettings(const ros::NodeHandle& pnh) const = 0;

 private:
  struct Channel {
    CameraChannelDefaults defaults;
    camera::SourceSpec source;
    std::string frame_id;
    std::string calibration_url;
    std::string calibration_file;  // for messages: the file behind the URL
    std::shared_ptr<camera_info_manager::CameraInfoManager> info_manager;
    image_transport::CameraPublisher publisher;
  };
  enum class State { kStarting, kStreaming, kWaiting, kRefused, kEnded };

  void readParameters();
  void readChannel(const docking_settings::ParamReader& reader, const camera::ChannelSettings& settings,
                   Channel& channel);
  /// The channel's camera_info_manager (in the camera's namespace) with its calibration loaded and checked.
  void loadCalibration(Channel& channel);
  /// The capture status and the publishing rate on /diagnostics.
  void startDiagnostics(const std::string& hardware_id);
  void captureLoop();
  void handleFrames(const std::vector<cv::Mat>& frames, const ros::Time& stamp);
  void diagnoseCapture(diagnostic_updater::DiagnosticStatusWrapper& status);

  const camera::ColourMode colour_mode_;
  std::vector<Channel> channels_;
  camera::CaptureSettings settings_;
  camera::BackoffParams backoff_;
  double rate_hz_ = 30.0;
  double rate_tolerance_ = 0.2;

  std::unique_ptr<image_transport::ImageTransport> image_transport_;
  std::unique_ptr<camera::CaptureRig> rig_;
  std::unique_ptr<diagnostic_updater::Updater> diagnostics_;
  std::unique_ptr<diagnostic_updater::FrequencyStatus> publish_rate_;
  double min_rate_hz_ = 0.0;
  double max_rate_hz_ = 0.0;

  // Capture-thread state (diagnostics run in the same thread, so no locking).
  State state_ = State::kStarting;
  std::string state_message_;
  double retry_in_s_ = 0.0;
  unsigned long frames_published_ = 0;
  unsigned long frames_refused_ = 0;
  unsigned long empty_frames_total_ = 0;
  unsigned long empty_frames_since_report_ = 0;

  std::atomic<bool> stop_{false};
  std::thread capture_thread_;
};

// Two sources published as stereo/{left,right}/{image_raw,camera_info}, bgr8 (mono8 for grey sources).
class StereoCameraNodelet : public CaptureNodelet {
 public:
  StereoCameraNodelet();

 protected:
  CameraSettings loadSettings(const ros::NodeHandle& pnh) const override;
};

// One source published as ir/{image_raw,camera_info}, always mono8.
class IrCameraNodelet : public CaptureNodelet {
 public:
  IrCameraNodelet();

 protected:
  CameraSettings loadSettings(const ros::NodeHandle& pnh) const override;
};

}  // namespace docking_perception
