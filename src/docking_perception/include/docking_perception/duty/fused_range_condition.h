// Does the arbiter's fused estimate (target/estimate) put the target on one side of a range, from a given
// source? (issue 15: cost proportional to need; ROS-free.) A stage that the current state does not use
// asks this to do less, and does its full work again, without waiting, as soon as the answer is no:
//   - disparity_detector rests (unsubscribes) while the target is INSIDE 0.8 m on a monocular pose:
//     there the arbiter never uses disparity (arbiter.yaml min_disparity_range_m 0.9 m);
//   - mono_pose processes at most far_max_rate_hz while the target is BEYOND 2.6 m on disparity: there
//     the arbiter uses disparity (switch_range_m 2.0 + hysteresis 0.2).
// The condition holds while the last fused estimate is fresh (arrived within max_fused_age_s), valid, from
// the wanted source and on the wanted side of range_m, with hysteresis: once holding, it holds until the
// target is hysteresis_m past range_m the other way. A stale estimate (the arbiter stalled or died), an
// invalid one or another source ends it at once.
#pragma once

namespace docking_perception {
namespace duty {

enum class RangeSide { kInside, kBeyond };

struct FusedRangeConditionParams {
  double range_m = 0.0;          // 0: never holds (the reduced duty is off)
  double hysteresis_m = 0.1;
  double max_fused_age_s = 0.3;  // by arrival time (ROS time)
};

// Why the condition holds or not, for diagnostics (no behaviour depends on a message's wording).
enum class FusedRangeState {
  kDisabled,         // range_m == 0
  kNoFusedEstimate,  // none received yet, or the last one is older than max_fused_age_s
  kFusedInvalid,     // the arbiter has nothing valid
  kOtherSource,      // the arbiter uses another source than the wanted one
  kOutOfRange,       // the target is on the other side of range_m (with hysteresis)
  kHolds,            // fresh, valid, the wanted source, on the wanted side
};

const char* describe(FusedRangeState state);

class FusedRangeCondition {
 public:
  explicit FusedRangeCondition(RangeSide side, const FusedRangeConditionParams& params = FusedRangeConditionParams())
      : side_(side), params_(params) {}
  void setParams(const FusedRangeConditionParams& params) { params_ = params; }
  const FusedRangeConditionParams& params() const { return params_; }

  // One fused estimate received at arrival_s (ROS time); wanted_source: its selected source is the one
  // this condition asks for.
  void onFusedEstimate(double arrival_s, bool valid, bool wanted_source, double range_m);
  // The state at now_s (ROS time); kHolds only while the last fused estimate is fresh.
  FusedRangeState state(double now_s) const;
  bool holds(double now_s) const { return state(now_s) == FusedRangeState::kHolds; }

 private:
  bool onWantedSide(double range_m, bool was_holding) const;

  RangeSide side_;
  FusedRangeConditionParams params_;
  bool have_estimate_ = false;
  double last_arrival_s_ = 0.0;
  FusedRangeState last_state_ = FusedRangeState::kNoFusedEstimate;  // from the last estimate alone
};

}  // namespace duty
}  // namespace docking_perception
