#include <gtest/gtest.h>

#include <cmath>

#include "docking_perception/duty/fused_range_condition.h"

using docking_perception::duty::FusedRangeCondition;
using docking_perception::duty::FusedRangeConditionParams;
using docking_perception::duty::FusedRangeState;
using docking_perception::duty::RangeSide;

namespace {

FusedRangeConditionParams params(double range_m) {
  FusedRangeConditionParams p;
  p.range_m = range_m;
  p.hysteresis_m = 0.1;
  p.max_fused_age_s = 0.3;
  return p;
}

}  // namespace

// The disparity detector's rest: inside 0.8 m on a monocular pose, until beyond 0.9 m.
TEST(FusedRangeCondition, InsideHoldsNearWithHysteresis) {
  FusedRangeCondition near(RangeSide::kInside, params(0.8));
  EXPECT_EQ(near.state(0.0), FusedRangeState::kNoFusedEstimate);
  near.onFusedEstimate(1.0, true, true, 1.5);
  EXPECT_EQ(near.state(1.0), FusedRangeState::kOutOfRange);
  near.onFusedEstimate(1.1, true, true, 0.85);  // in the band, not yet holding: still out
  EXPECT_EQ(near.state(1.1), FusedRangeState::kOutOfRange);
  near.onFusedEstimate(1.2, true, true, 0.79);
  EXPECT_TRUE(near.holds(1.2));
  near.onFusedEstimate(1.3, true, true, 0.88);  // in the band, holding: holds
  EXPECT_TRUE(near.holds(1.3));
  near.onFusedEstimate(1.4, true, true, 0.91);  // beyond 0.8 + 0.1
  EXPECT_EQ(near.state(1.4), FusedRangeState::kOutOfRange);
}

// mono_pose's far throttle: beyond 2.6 m on disparity, until inside 2.5 m.
TEST(FusedRangeCondition, BeyondHoldsFarWithHysteresis) {
  FusedRangeCondition far(RangeSide::kBeyond, params(2.6));
  far.onFusedEstimate(1.0, true, true, 2.55);
  EXPECT_EQ(far.state(1.0), FusedRangeState::kOutOfRange);
  far.onFusedEstimate(1.1, true, true, 4.0);
  EXPECT_TRUE(far.holds(1.1));
  far.onFusedEstimate(1.2, true, true, 2.55);  // in the band, holding
  EXPECT_TRUE(far.holds(1.2));
  far.onFusedEstimate(1.3, true, true, 2.45);
  EXPECT_EQ(far.state(1.3), FusedRangeState::kOutOfRange);
}

// Every way the estimate can stop being trustworthy ends the condition at once.
TEST(FusedRangeCondition, EndsWhenTheArbiterFallsBackStallsOrLosesTheTarget) {
  FusedRangeCondition near(RangeSide::kInside, params(0.8));
  near.onFusedEstimate(1.0, true, true, 0.5);
  ASSERT_TRUE(near.holds(1.0));
  EXPECT_TRUE(near.holds(1.29));
  EXPECT_EQ(near.state(1.31), FusedRangeState::kNoFusedEstimate);  // the arbiter went silent

  near.onFusedEstimate(2.0, true, true, 0.5);
  ASSERT_TRUE(near.holds(2.0));
  near.onFusedEstimate(2.1, false, false, 0.0);
  EXPECT_EQ(near.state(2.1), FusedRangeState::kFusedInvalid);

  near.onFusedEstimate(3.0, true, true, 0.5);
  ASSERT_TRUE(near.holds(3.0));
  near.onFusedEstimate(3.1, true, false, 0.5);
  EXPECT_EQ(near.state(3.1), FusedRangeState::kOtherSource);

  near.onFusedEstimate(4.0, true, true, std::nan(""));
  EXPECT_EQ(near.state(4.0), FusedRangeState::kFusedInvalid);
}

// After a silence the hysteresis does not carry over.
TEST(FusedRangeCondition, HysteresisNeedsAFreshHold) {
  FusedRangeCondition near(RangeSide::kInside, params(0.8));
  near.onFusedEstimate(1.0, true, true, 0.5);
  ASSERT_TRUE(near.holds(1.0));
  near.onFusedEstimate(5.0, true, true, 0.85);
  EXPECT_EQ(near.state(5.0), FusedRangeState::kOutOfRange);
}

TEST(FusedRangeCondition, ZeroRangeDisables) {
  FusedRangeCondition near(RangeSide::kInside, params(0.0));
  near.onFusedEstimate(1.0, true, true, 0.2);
  EXPECT_EQ(near.state(1.0), FusedRangeState::kDisabled);
}
