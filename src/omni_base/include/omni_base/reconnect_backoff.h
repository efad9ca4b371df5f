// Exponential back-off between reconnection attempts (ROS-free).
#pragma once

#include <algorithm>
#include <stdexcept>

namespace omni_base {

/// Doubles the wait after each failed attempt, from min_s up to max_s; success starts over. A board
/// that is unplugged is then polled often at first and gently after a while, never in a busy loop.
class ReconnectBackoff {
 public:
  ReconnectBackoff(double min_s, double max_s) : min_s_(min_s), max_s_(max_s), next_s_(min_s) {
    if (!(min_s > 0.0) || !(max_s >= min_s)) throw std::invalid_argument("back-off needs 0 < min <= max");
  }
  /// The wait before the next attempt; each call doubles the following one.
  double nextDelay() {
    const double d = next_s_;
    next_s_ = std::min(max_s_, next_s_ * 2.0);
    return d;
  }
  void reset() { next_s_ = min_s_; }

 private:
  double min_s_;
  double max_s_;
  double next_s_;
};

}  // namespace omni_base
