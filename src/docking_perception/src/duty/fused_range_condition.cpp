#include "docking_perception/duty/fused_range_condition.h"

#include <cmath>

namespace docking_perception {
namespace duty {

const char* describe(FusedRangeState state) {
  switch (state) {
    case FusedRangeState::kDisabled: return "off (range 0)";
    case FusedRangeState::kNoFusedEstimate: return "no recent fused estimate";
    case FusedRangeState::kFusedInvalid: return "the fused estimate is not valid";
    case FusedRangeState::kOtherSource: return "the arbiter uses another source";
    case FusedRangeState::kOutOfRange: return "the target is on the other side of the range";
    case FusedRangeState::kHolds: return "holds";
  }
  return "unknown";
}

bool FusedRangeCondition::onWantedSide(double range_m, bool was_holding) const {
  // Hysteresis: once holding, the limit moves hysteresis_m the other way.
  const double margin = was_holding ? params_.hysteresis_m : 0.0;
  return side_ == RangeSide::kInside ? range_m < params_.range_m + margin : range_m > params_.range_m - margin;
}

void FusedRangeCondition::onFusedEstimate(double arrival_s, bool valid, bool wanted_source, double range_m) {
  const bool was_holding = have_estimate_ && last_state_ == FusedRangeState::kHolds &&
                           arrival_s - last_arrival_s_ <= params_.max_fused_age_s;
  have_estimate_ = true;
  last_arrival_s_ = arrival_s;
  if (!valid || !std::isfinite(range_m)) {
    last_state_ = FusedRangeState::kFusedInvalid;
  } else if (!wanted_source) {
    last_state_ = FusedRangeState::kOtherSource;
  } else {
    last_state_ = onWantedSide(range_m, was_holding) ? FusedRangeState::kHolds : FusedRangeState::kOutOfRange;
  }
}

FusedRangeState FusedRangeCondition::state(double now_s) const {
  if (params_.range_m <= 0.0) return FusedRangeState::kDisabled;
  if (!have_estimate_ || now_s - last_arrival_s_ > params_.max_fused_age_s) return FusedRangeState::kNoFusedEstimate;
  return last_state_;
}

}  // namespace duty
}  // namespace docking_perception
