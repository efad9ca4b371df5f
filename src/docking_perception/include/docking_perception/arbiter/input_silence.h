// Whether the estimators are still talking (ROS-free). The arbiter re-publishes "nothing valid" on its
// own timer, so a planner downstream cannot tell "the target is not seen" from "perception is gone"
// unless the arbiter says which: a stalled or dead perception must stop the chaser, not send it
// searching.
#pragma once

#include <limits>
#include <stdexcept>

namespace docking_perception {
namespace arbiter {

class InputSilence {
 public:
  /// timeout_s: no message from any estimator for longer than this is silence.
  explicit InputSilence(double timeout_s) : timeout_s_(timeout_s) {
    if (!(timeout_s > 0.0) || !(timeout_s < kMaxTimeoutS)) {
      throw std::invalid_argument("sources_silent_timeout_s must be in (0, 10) s");
    }
  }

  /// An estimator's message arrived at `now_s` (receipt time, not its stamp: a message with a bad stamp
  /// still shows that its sender is alive).
  void noteArrival(double now_s) { last_arrival_s_ = now_s; }

  /// Silent at `now_s`: nothing arrived yet, or nothing for longer than the timeout. A clock that went
  /// back (a bag looped, the simulator restarted) counts as an arrival now, not as silence forever.
  bool silent(double now_s) {
    if (now_s < last_arrival_s_) last_arrival_s_ = now_s;
    return !(now_s - last_arrival_s_ <= timeout_s_);
  }

  /// Seconds since the last arrival (infinite before the first).
  double silentFor(double now_s) const { return now_s - last_arrival_s_; }
  /// Whether any estimator has published since start (before that, silentFor() is infinite).
  bool heardAny() const { return last_arrival_s_ > -std::numeric_limits<double>::infinity(); }
  double timeout() const { return timeout_s_; }

  static constexpr double kMaxTimeoutS = 10.0;

 private:
  double timeout_s_;
  double last_arrival_s_{-std::numeric_limits<double>::infinity()};
};

}  // namespace arbiter
}  // namespace docking_perception
