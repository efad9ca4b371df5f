#include "docking_perception/disparity/near_range_pause.h"

#include <cmath>

namespace docking_perception {
namespace disparity {

const char* describe(PauseState state) {
  switch (state) {
    case PauseState::kDisabled: return "running: pausing disabled (pause_inside_range_m 0)";
    case PauseState::kNoFusedEstimate: return "running: no recent fused estimate";
    case PauseState::kFusedInvalid: return "running: the fused estimate is not valid";
    case PauseState::kFusedNotMono: return "running: the arbiter uses disparity";
    case PauseState::kBeyondRange: return "running: the target is beyond the pause range";
    case PauseState::kPaused: return "paused: target near, the arbiter on a monocular pose";
  }
  return "unknown";
}

void NearRangePause::onFusedEstimate(double arrival_s, bool valid, bool from_monocular, double range_m) {
  const bool was_paused = have_estimate_ && last_state_ == PauseState::kPaused &&
                          arrival_s - last_arrival_s_ <= params_.max_fused_age_s;
  have_estimate_ = true;
  last_arrival_s_ = arrival_s;
  if (!valid || !std::isfinite(range_m)) {
    last_state_ = PauseState::kFusedInvalid;
  } else if (!from_monocular) {
    last_state_ = PauseState::kFusedNotMono;
  } else {
    // Hysteresis: once paused, stay paused until the target is clearly beyond the range.
    const double limit = was_paused ? params_.pause_inside_range_m + params_.hysteresis_m
                                    : params_.pause_inside_range_m;
    last_state_ = range_m < limit ? PauseState::kPaused : PauseState::kBeyondRange;
  }
}

PauseState NearRangePause::state(double now_s) const {
  if (params_.pause_inside_range_m <= 0.0) return PauseState::kDisabled;
  if (!have_estimate_ || now_s - last_arrival_s_ > params_.max_fused_age_s) return PauseState::kNoFusedEstimate;
  return last_state_;
}

}  // namespace disparity
}  // namespace docking_perception
