// Exponential back-off between attempts to (re)open a device: the motor board's serial port (omni_base)
// and the cameras (docking_perception). ROS-free, one copy. An unplugged device is polled often at first
// and gently after a while, never in a busy loop; a success starts over.
#pragma once

#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <string>

namespace docking_msgs {

struct BackoffParams {
  double initial_s = 0.5;  ///< delay after the first failure
  double max_s = 8.0;      ///< the delay never grows beyond this
  double factor = 2.0;     ///< each further failure multiplies the delay by this
};

/// Throws std::invalid_argument naming the field (initial_s, max_s, factor) when the values cannot make a
/// schedule: non-positive or non-finite delays, max_s < initial_s, factor < 1.
inline void validateBackoffParams(const BackoffParams& params) {
  if (!std::isfinite(params.initial_s) || params.initial_s <= 0.0) {
    throw std::invalid_argument("initial_s must be a positive number of seconds, got " + std::to_string(params.initial_s));
  }
  if (!std::isfinite(params.max_s) || params.max_s < params.initial_s) {
    throw std::invalid_argument("max_s must be at least initial_s (" + std::to_string(params.initial_s) + " s), got " +
                                std::to_string(params.max_s));
  }
  if (!std::isfinite(params.factor) || params.factor < 1.0) {
    throw std::invalid_argument("factor must be at least 1, got " + std::to_string(params.factor));
  }
}

class ReconnectBackoff {
 public:
  explicit ReconnectBackoff(const BackoffParams& params) : params_(params), next_delay_s_(params.initial_s) {
    validateBackoffParams(params_);
  }
  /// The delay to wait after one more failure; the following call returns a longer one (up to max_s).
  double nextDelay() {
    const double delay = next_delay_s_;
    next_delay_s_ = std::min(params_.max_s, next_delay_s_ * params_.factor);
    ++failures_;
    return delay;
  }
  /// After a success: the next failure waits initial_s again.
  void reset() {
    next_delay_s_ = params_.initial_s;
    failures_ = 0;
  }
  /// Failures since the last reset().
  int failures() const { return failures_; }

 private:
  BackoffParams params_;
  double next_delay_s_;
  int failures_ = 0;
};

}  // namespace docking_msgs
