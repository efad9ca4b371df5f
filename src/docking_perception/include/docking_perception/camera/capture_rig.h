// One or more capture sources read as a set (a stereo pair: both grabbed before either is decoded),
// with the device life cycle: open, apply settings, lose, retry with backoff, loop or end a file.
// ROS-free: time comes in as a monotonic number of seconds, so tests drive it without sleeping.
#pragma once

#include <docking_msgs/reconnect_backoff.h>
#include <docking_perception/camera/source_spec.h>

#include <opencv2/core.hpp>
#include <opencv2/videoio.hpp>

#include <functional>
#include <string>
#include <vector>

namespace docking_perception {
namespace camera {

using docking_msgs::BackoffParams;
using docking_msgs::ReconnectBackoff;
using docking_msgs::validateBackoffParams;

struct CaptureSettings {
  int width = 640;          // requested from devices; files and sequences keep their own size
  int height = 480;
  double fps = 30.0;        // requested from devices
  std::string fourcc;       // e.g. "MJPG" (two USB 2 webcams on one bus need it); empty: driver default
  bool loop_files = true;   // a file or sequence starts again at its end (otherwise: end of stream)
  int max_consecutive_empty = 30;  // this many empty frames in a row count as a lost device
};

// Throws std::invalid_argument naming the field when a setting is out of range.
void validateCaptureSettings(const CaptureSettings& settings);

enum class CaptureStatus {
  kFrames,       // `frames` holds one frame per source, in source order
  kEmptyFrame,   // a source gave an empty frame: skip it (message names the source)
  kWaiting,      // no open sources: a (re)open failed or a device was lost; next attempt at retry_at_s
  kRestarted,    // files or sequences reached their end and were reopened (loop_files)
  kEndOfStream,  // files or sequences reached their end and loop_files is off: nothing more will come
};

const char* toString(CaptureStatus status);

struct CaptureOutcome {
  CaptureStatus status = CaptureStatus::kWaiting;
  std::vector<cv::Mat> frames;
  std::string message;      // for kWaiting / kEmptyFrame / kRestarted / kEndOfStream: what happened
  double retry_at_s = 0.0;  // kWaiting: when capture() will try to open again
  bool new_failure = false; // kWaiting: this call tried to open, or lost a device (false: still waiting)
};

class CaptureRig {
 public:
  // Throws std::invalid_argument for no sources or invalid settings / backoff.
  CaptureRig(std::vector<SourceSpec> sources, const CaptureSettings& settings, const BackoffParams& backoff);
  ~CaptureRig();
  CaptureRig(const CaptureRig&) = delete;
  CaptureRig& operator=(const CaptureRig&) = delete;

  // Produces one set of frames if it can (frames stay valid until the next call). Opens the sources first when they are closed and the retry
  // time has come; otherwise returns kWaiting at once. `after_grab` (optional) runs once every source
  // has grabbed and before any frame is decoded: the moment to take the set's time stamp.
  CaptureOutcome capture(double now_s, const std::function<void()>& after_grab = {});

  bool isOpen() const { return open_; }
  const std::vector<SourceSpec>& sources() const { return sources_; }
  // Failed open attempts or losses since the last good set of frames.
  int consecutiveFailures() const { return backoff_.failures(); }
  // Sizes the sources actually deliver once open (devices may not honour the requested size).
  std::vector<cv::Size> openedSizes() const;
  void close();

 private:
  bool openAll(std::string* error);
  bool openOne(size_t index, std::string* error);
  CaptureOutcome scheduleRetry(double now_s, const std::string& what);
  bool allFiles() const;
  bool reachedKnownEnd() const;
  CaptureOutcome endOfFiles(double now_s, const std::string& end);

  std::vector<SourceSpec> sources_;
  CaptureSettings settings_;
  ReconnectBackoff backoff_;
  std::vector<cv::VideoCapture> captures_;
  bool open_ = false;
  bool ended_ = false;
  double retry_at_s_ = 0.0;
  std::string last_error_;
  long frames_since_open_ = 0;
  std::vector<long> frame_counts_;  // frames in each file or sequence (0: unknown or a live device)
  int consecutive_empty_ = 0;
};

}  // namespace camera
}  // namespace docking_perception
