#include <gtest/gtest.h>

#include <cmath>

#include "docking_perception/disparity/near_range_pause.h"

using docking_perception::disparity::NearRangePause;
using docking_perception::disparity::NearRangePauseParams;
using docking_perception::disparity::PauseState;

namespace {

NearRangePauseParams params() {
  NearRangePauseParams p;
  p.pause_inside_range_m = 0.8;
  p.hysteresis_m = 0.1;
  p.max_fused_age_s = 0.3;
  return p;
}

}  // namespace

TEST(NearRangePause, PausesOnlyNearOnAMonocularEstimateWithHysteresis) {
  NearRangePause pause(params());
  EXPECT_EQ(pause.state(0.0), PauseState::kNoFusedEstimate);
  pause.onFusedEstimate(1.0, true, true, 1.5);
  EXPECT_EQ(pause.state(1.0), PauseState::kBeyondRange);
  pause.onFusedEstimate(1.1, true, true, 0.85);  // inside the hysteresis band, not yet paused: stays running
  EXPECT_EQ(pause.state(1.1), PauseState::kBeyondRange);
  pause.onFusedEstimate(1.2, true, true, 0.79);
  EXPECT_TRUE(pause.paused(1.2));
  pause.onFusedEstimate(1.3, true, true, 0.88);  // in the band, paused: stays paused
  EXPECT_TRUE(pause.paused(1.3));
  pause.onFusedEstimate(1.4, true, true, 0.91);  // beyond 0.8 + 0.1
  EXPECT_EQ(pause.state(1.4), PauseState::kBeyondRange);
}

// Every way the near, monocular estimate can stop being trustworthy resumes the stage at once.
TEST(NearRangePause, ResumesWhenTheArbiterFallsBackStallsOrLosesTheTarget) {
  NearRangePause pause(params());
  pause.onFusedEstimate(1.0, true, true, 0.5);
  ASSERT_TRUE(pause.paused(1.0));
  EXPECT_TRUE(pause.paused(1.29));
  EXPECT_EQ(pause.state(1.31), PauseState::kNoFusedEstimate);  // the arbiter went silent

  pause.onFusedEstimate(2.0, true, true, 0.5);
  ASSERT_TRUE(pause.paused(2.0));
  pause.onFusedEstimate(2.1, false, false, 0.0);
  EXPECT_EQ(pause.state(2.1), PauseState::kFusedInvalid);

  pause.onFusedEstimate(3.0, true, true, 0.5);
  ASSERT_TRUE(pause.paused(3.0));
  pause.onFusedEstimate(3.1, true, false, 0.5);
  EXPECT_EQ(pause.state(3.1), PauseState::kFusedNotMono);

  pause.onFusedEstimate(4.0, true, true, std::nan(""));
  EXPECT_EQ(pause.state(4.0), PauseState::kFusedInvalid);
}

// After a silence the hysteresis does not carry over: a stale pause is not resumed from the band.
TEST(NearRangePause, HysteresisNeedsAFreshPause) {
  NearRangePause pause(params());
  pause.onFusedEstimate(1.0, true, true, 0.5);
  ASSERT_TRUE(pause.paused(1.0));
  pause.onFusedEstimate(5.0, true, true, 0.85);
  EXPECT_EQ(pause.state(5.0), PauseState::kBeyondRange);
}

TEST(NearRangePause, ZeroRangeDisables) {
  NearRangePauseParams p = params();
  p.pause_inside_range_m = 0.0;
  NearRangePause pause(p);
  pause.onFusedEstimate(1.0, true, true, 0.2);
  EXPECT_EQ(pause.state(1.0), PauseState::kDisabled);
}
