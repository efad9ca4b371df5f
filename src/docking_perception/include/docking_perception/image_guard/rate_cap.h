// Frames passed at most max_rate_hz, decided by stamp (issue 15; ROS-free). perception.launch caps the
// right stereo camera: its images feed only block matching, which the far stage needs at 7.5 Hz, not at
// the camera's 30 Hz. The left camera (mono_pose and the matcher's other half) is not capped; the
// matcher pairs by stamp, so it runs on the capped frames only.
// Decided by the stamp, not arrival: an image and its camera_info (either may come first) get the same
// answer, and a replay decides as the live run did.
#pragma once

#include <cstddef>
#include <deque>
#include <utility>

namespace docking_perception {
namespace image_guard {

class RateCap {
 public:
  // Admitted when at least (1 - kJitterFraction) of the period after the last admitted stamp, so a
  // frame that comes a little early is not pushed to the next one. 10 %: a 7.5 Hz cap passes every
  // second frame of a 15 Hz camera and every fourth of a 30 Hz one (7.5 Hz both), with a few ms of
  // jitter either way.
  static constexpr double kJitterFraction = 0.1;
  // Decisions remembered (the image and the info of one stamp arrive within a few frames of each other).
  static constexpr std::size_t kRememberedStamps = 16;

  explicit RateCap(double max_rate_hz = 0.0) : max_rate_hz_(max_rate_hz) {}
  double maxRateHz() const { return max_rate_hz_; }
  // A new cap from the next undecided stamp on (stamps already decided keep their answer): the right
  // camera's guard slows block matching to a keep-alive rate while the arbiter is on a monocular pose.
  void setMaxRateHz(double max_rate_hz) { max_rate_hz_ = max_rate_hz; }

  // Whether the frame stamped stamp_s passes. The same stamp gets the same answer; max_rate_hz 0 passes
  // all; a stamp before the last admitted one (a replay looped, the simulator restarted) starts over.
  bool admit(double stamp_s);

 private:
  double max_rate_hz_;
  bool have_admitted_ = false;
  double last_admitted_s_ = 0.0;
  std::deque<std::pair<double, bool>> decisions_;  // (stamp, admitted), newest last
};

}  // namespace image_guard
}  // namespace docking_perception
