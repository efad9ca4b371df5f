// Exponential backoff between attempts to (re)open a capture device. ROS-free.
#pragma once

namespace docking_perception {
namespace camera {

struct BackoffParams {
  double initial_s = 0.5;  // delay after the first failure
  double max_s = 8.0;      // the delay never grows beyond this
  double factor = 2.0;     // each further failure multiplies the delay by this
};

// Throws std::invalid_argument naming the field (initial_s, max_s, factor) when the values cannot make a
// schedule: non-positive or non-finite delays, max_s < initial_s, factor < 1.
void validateBackoffParams(const BackoffParams& params);

class ReconnectBackoff {
 public:
  explicit ReconnectBackoff(const BackoffParams& params);  // validates, see validateBackoffParams

  // The delay to wait after one more failure; the following call returns a longer one (up to max_s).
  double nextDelay();
  // After a success: the next failure waits initial_s again.
  void reset();
  // Failures since the last reset().
  int failures() const { return failures_; }

 private:
  BackoffParams params_;
  double next_delay_s_;
  int failures_ = 0;
};

}  // namespace camera
}  // namespace docking_perception
