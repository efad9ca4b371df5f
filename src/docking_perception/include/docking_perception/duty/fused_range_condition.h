// When may the disparity stage stop? (issue 15: cost proportional to need; ROS-free.)
// Near the target the arbiter never uses disparity (config/arbiter.yaml min_disparity_range_m: 0.9 m),
// yet block matching is most of perception's CPU. The detector follows the arbiter's fused estimate
// (target/estimate) and pauses while that estimate is fresh, valid, comes from a monocular source and
// is nearer than pause_inside_range_m. It resumes, without waiting, when any of that stops being true:
// the estimate moves out past pause_inside_range_m + hysteresis_m, the arbiter falls back to disparity
// or has nothing valid, or no fused estimate arrived for max_fused_age_s (the arbiter stalled).
#pragma once

namespace docking_perception {
namespace disparity {

struct NearRangePauseParams {
  double pause_inside_range_m = 0.0;  // 0: never pause
  double hysteresis_m = 0.1;          // resume beyond pause_inside_range_m + this
  double max_fused_age_s = 0.3;       // an older fused estimate (by arrival time) resumes the stage
};

// Why the stage runs or rests, for diagnostics (no behaviour depends on a message's wording).
enum class PauseState {
  kDisabled,        // pause_inside_range_m == 0
  kNoFusedEstimate, // none received yet, or the last one is older than max_fused_age_s
  kFusedInvalid,    // the arbiter has nothing valid
  kFusedNotMono,    // the arbiter uses disparity (or an unknown source)
  kBeyondRange,     // the fused estimate is farther than the pause range (with hysteresis)
  kPaused,          // near, on a monocular source: the stage rests
};

const char* describe(PauseState state);

class NearRangePause {
 public:
  explicit NearRangePause(const NearRangePauseParams& params = NearRangePauseParams()) : params_(params) {}
  void setParams(const NearRangePauseParams& params) { params_ = params; }
  const NearRangePauseParams& params() const { return params_; }

  // One fused estimate, received at arrival_s (ROS time).
  void onFusedEstimate(double arrival_s, bool valid, bool from_monocular, double range_m);
  // The state at now_s (ROS time); kPaused only while the last fused estimate is fresh.
  PauseState state(double now_s) const;
  bool paused(double now_s) const { return state(now_s) == PauseState::kPaused; }

 private:
  NearRangePauseParams params_;
  bool have_estimate_ = false;
  double last_arrival_s_ = 0.0;
  PauseState last_state_ = PauseState::kNoFusedEstimate;  // from the last estimate alone
};

}  // namespace disparity
}  // namespace docking_perception
