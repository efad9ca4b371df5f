#include <gtest/gtest.h>

#include <cmath>
#include <stdexcept>

#include "docking_perception/arbiter/source_arbiter.h"

using docking_perception::arbiter::ArbiterConfig;
using docking_perception::arbiter::Decision;
using docking_perception::arbiter::EstimateSummary;
using docking_perception::arbiter::RangeRegime;
using docking_perception::arbiter::Source;
using docking_perception::arbiter::SourceArbiter;

namespace {

EstimateSummary good(Source source, double stamp, double range) {
  EstimateSummary e;
  e.source = source;
  e.stamp_s = stamp;
  e.valid = true;
  e.position_valid = true;
  e.orientation_valid = source != Source::kDisparity;
  e.range_m = range;
  e.feature_inliers = source == Source::kDisparity ? 500 : 40;
  e.reprojection_error_px = source == Source::kDisparity ? 0.0 : 0.6;
  return e;
}

EstimateSummary lost(Source source, double stamp) {
  EstimateSummary e;
  e.source = source;
  e.stamp_s = stamp;
  e.valid = false;
  e.status = "no contour";
  return e;
}

// Offers all three sources at the same stamp and range, and decides at that time.
Decision offerAll(SourceArbiter& arbiter, double stamp, double range) {
  EXPECT_TRUE(arbiter.offer(good(Source::kDisparity, stamp, range)).accepted);
  EXPECT_TRUE(arbiter.offer(good(Source::kMonoVisible, stamp, range)).accepted);
  EXPECT_TRUE(arbiter.offer(good(Source::kMonoIr, stamp, range)).accepted);
  return arbiter.decide(stamp + 0.01);
}

}  // namespace

TEST(SourceArbiter, RejectsInvalidConfiguration) {
  ArbiterConfig c;
  c.hysteresis_m = 2.5;  // larger than the switch range
  EXPECT_THROW(SourceArbiter{c}, std::invalid_argument);
  c = ArbiterConfig{};
  c.timeout_s = NAN;
  EXPECT_THROW(SourceArbiter{c}, std::invalid_argument);
  c = ArbiterConfig{};
  c.switch_range_m = -1.0;
  EXPECT_THROW(SourceArbiter{c}, std::invalid_argument);
}

TEST(SourceArbiter, DisparityFarMonoNear) {
  SourceArbiter far_arbiter{ArbiterConfig{}};
  Decision d = offerAll(far_arbiter, 10.0, 3.5);
  ASSERT_TRUE(d.valid);
  EXPECT_EQ(d.source, Source::kDisparity);
  EXPECT_EQ(d.regime, RangeRegime::kFar);

  SourceArbiter near_arbiter{ArbiterConfig{}};
  d = offerAll(near_arbiter, 10.0, 1.2);
  ASSERT_TRUE(d.valid);
  EXPECT_EQ(d.source, Source::kMonoVisible);
  EXPECT_EQ(d.regime, RangeRegime::kNear);
  EXPECT_NE(d.reason.find("mono_visible"), std::string::npos);
}

TEST(SourceArbiter, HysteresisApproachingStaysOnDisparityUntilBelowBand) {
  SourceArbiter arbiter{ArbiterConfig{}};  // switch 2.0, hysteresis 0.2
  double t = 0.0;
  EXPECT_EQ(offerAll(arbiter, t += 0.1, 2.5).source, Source::kDisparity);
  EXPECT_EQ(offerAll(arbiter, t += 0.1, 1.95).source, Source::kDisparity);  // inside the band
  EXPECT_EQ(offerAll(arbiter, t += 0.1, 1.85).source, Source::kDisparity);
  EXPECT_EQ(offerAll(arbiter, t += 0.1, 1.75).source, Source::kMonoVisible);  // below 1.8
  // Noise back up into the band does not switch back.
  EXPECT_EQ(offerAll(arbiter, t += 0.1, 2.1).source, Source::kMonoVisible);
  EXPECT_EQ(offerAll(arbiter, t += 0.1, 1.9).source, Source::kMonoVisible);
}

TEST(SourceArbiter, HysteresisRetreatingStaysOnMonoUntilAboveBand) {
  SourceArbiter arbiter{ArbiterConfig{}};
  double t = 0.0;
  EXPECT_EQ(offerAll(arbiter, t += 0.1, 1.0).source, Source::kMonoVisible);
  EXPECT_EQ(offerAll(arbiter, t += 0.1, 2.15).source, Source::kMonoVisible);
  EXPECT_EQ(offerAll(arbiter, t += 0.1, 2.25).source, Source::kDisparity);  // above 2.2
  EXPECT_EQ(offerAll(arbiter, t += 0.1, 1.9).source, Source::kDisparity);   // band: stays far
}

TEST(SourceArbiter, ChatterAroundSwitchRangeCausesNoSwitches) {
  SourceArbiter arbiter{ArbiterConfig{}};
  double t = 0.0;
  const Source first = offerAll(arbiter, t += 0.1, 2.0).source;
  for (int i = 0; i < 50; ++i) {
    const double range = 2.0 + 0.15 * std::sin(0.7 * i);  // stays within +-0.15 m of 2 m
    EXPECT_EQ(offerAll(arbiter, t += 0.1, range).source, first) << "i=" << i;
  }
}

TEST(SourceArbiter, PoorVisibleFallsBackToIr) {
  SourceArbiter arbiter{ArbiterConfig{}};
  EstimateSummary dark = good(Source::kMonoVisible, 1.0, 1.0);
  dark.feature_inliers = 4;  // dark scene: few inliers
  ASSERT_TRUE(arbiter.offer(dark).accepted);
  ASSERT_TRUE(arbiter.offer(good(Source::kMonoIr, 1.0, 1.0)).accepted);
  ASSERT_TRUE(arbiter.offer(good(Source::kDisparity, 1.0, 1.0)).accepted);
  Decision d = arbiter.decide(1.05);
  ASSERT_TRUE(d.valid);
  EXPECT_EQ(d.source, Source::kMonoIr);
  EXPECT_NE(d.reason.find("inliers"), std::string::npos) << d.reason;

  EstimateSummary glare = good(Source::kMonoVisible, 1.1, 1.0);
  glare.reprojection_error_px = 9.0;  // glare: high reprojection error
  ASSERT_TRUE(arbiter.offer(glare).accepted);
  ASSERT_TRUE(arbiter.offer(good(Source::kMonoIr, 1.1, 1.0)).accepted);
  d = arbiter.decide(1.15);
  EXPECT_EQ(d.source, Source::kMonoIr);
  EXPECT_NE(d.reason.find("reprojection"), std::string::npos) << d.reason;

  // The visible image recovers: back to the visible camera.
  ASSERT_TRUE(arbiter.offer(good(Source::kMonoVisible, 1.2, 1.0)).accepted);
  ASSERT_TRUE(arbiter.offer(good(Source::kMonoIr, 1.2, 1.0)).accepted);
  EXPECT_EQ(arbiter.decide(1.25).source, Source::kMonoVisible);
}

TEST(SourceArbiter, InvalidVisibleFallsBackToIrThenToDisparity) {
  SourceArbiter arbiter{ArbiterConfig{}};
  ASSERT_TRUE(arbiter.offer(lost(Source::kMonoVisible, 1.0)).accepted);
  ASSERT_TRUE(arbiter.offer(good(Source::kMonoIr, 1.0, 1.0)).accepted);
  ASSERT_TRUE(arbiter.offer(good(Source::kDisparity, 1.0, 1.0)).accepted);
  EXPECT_EQ(arbiter.decide(1.01).source, Source::kMonoIr);

  ASSERT_TRUE(arbiter.offer(lost(Source::kMonoVisible, 1.1)).accepted);
  ASSERT_TRUE(arbiter.offer(lost(Source::kMonoIr, 1.1)).accepted);
  ASSERT_TRUE(arbiter.offer(good(Source::kDisparity, 1.1, 1.0)).accepted);
  const Decision d = arbiter.decide(1.11);
  ASSERT_TRUE(d.valid);
  EXPECT_EQ(d.source, Source::kDisparity);
  EXPECT_EQ(d.regime, RangeRegime::kNear);  // still near: disparity is only the fallback
}

TEST(SourceArbiter, FarDisparityDropoutUsesMono) {
  SourceArbiter arbiter{ArbiterConfig{}};
  EXPECT_EQ(offerAll(arbiter, 1.0, 3.0).source, Source::kDisparity);
  ASSERT_TRUE(arbiter.offer(lost(Source::kDisparity, 1.1)).accepted);
  ASSERT_TRUE(arbiter.offer(good(Source::kMonoVisible, 1.1, 3.0)).accepted);
  const Decision d = arbiter.decide(1.12);
  ASSERT_TRUE(d.valid);
  EXPECT_EQ(d.source, Source::kMonoVisible);
  EXPECT_EQ(d.regime, RangeRegime::kFar);
  EXPECT_NE(d.reason.find("disparity no target"), std::string::npos) << d.reason;
}

TEST(SourceArbiter, StaleEstimatesAreNeverUsed) {
  ArbiterConfig c;
  c.timeout_s = 0.5;
  SourceArbiter arbiter{c};
  ASSERT_TRUE(arbiter.offer(good(Source::kMonoVisible, 1.0, 1.0)).accepted);
  ASSERT_TRUE(arbiter.offer(good(Source::kDisparity, 1.3, 1.0)).accepted);
  // At 1.45 both are fresh: mono is preferred near.
  EXPECT_EQ(arbiter.decide(1.45).source, Source::kMonoVisible);
  // At 1.6 mono is 0.6 s old: disparity (0.3 s old) is used.
  Decision d = arbiter.decide(1.6);
  ASSERT_TRUE(d.valid);
  EXPECT_EQ(d.source, Source::kDisparity);
  EXPECT_NE(d.reason.find("stale"), std::string::npos) << d.reason;
  // At 2.0 both are stale: nothing.
  d = arbiter.decide(2.0);
  EXPECT_FALSE(d.valid);
  EXPECT_NE(d.reason.find("no usable estimate"), std::string::npos) << d.reason;
}

TEST(SourceArbiter, OutOfOrderAndDuplicateStampsAreRejected) {
  SourceArbiter arbiter{ArbiterConfig{}};
  ASSERT_TRUE(arbiter.offer(good(Source::kMonoVisible, 2.0, 1.0)).accepted);
  const auto older = arbiter.offer(good(Source::kMonoVisible, 1.9, 0.5));
  EXPECT_FALSE(older.accepted);
  EXPECT_NE(older.reason.find("out of order"), std::string::npos);
  EXPECT_FALSE(arbiter.offer(good(Source::kMonoVisible, 2.0, 0.5)).accepted);
  EXPECT_FALSE(arbiter.offer(good(Source::kMonoVisible, NAN, 0.5)).accepted);
  EXPECT_EQ(arbiter.rejectedCount(), 3u);
  // The kept estimate is the first one.
  EXPECT_DOUBLE_EQ(arbiter.latest(Source::kMonoVisible)->range_m, 1.0);
  // Another source keeps its own order.
  EXPECT_TRUE(arbiter.offer(good(Source::kMonoIr, 1.9, 1.0)).accepted);
}

TEST(SourceArbiter, EachEstimateIsNewOnceAndOutputStaysInOrder) {
  SourceArbiter arbiter{ArbiterConfig{}};
  ASSERT_TRUE(arbiter.offer(good(Source::kDisparity, 5.0, 1.0)).accepted);
  Decision d = arbiter.decide(5.01);
  EXPECT_TRUE(d.is_new);
  EXPECT_EQ(d.source, Source::kDisparity);
  EXPECT_FALSE(arbiter.decide(5.02).is_new);  // same estimate again

  // A mono estimate arrives late, stamped before the published disparity one: preferred, but not
  // published, since it would step the output back in time.
  ASSERT_TRUE(arbiter.offer(good(Source::kMonoVisible, 4.95, 1.0)).accepted);
  d = arbiter.decide(5.03);
  EXPECT_TRUE(d.valid);
  EXPECT_EQ(d.source, Source::kMonoVisible);
  EXPECT_FALSE(d.is_new);
  // The next mono estimate is newer: published.
  ASSERT_TRUE(arbiter.offer(good(Source::kMonoVisible, 5.05, 1.0)).accepted);
  d = arbiter.decide(5.06);
  EXPECT_TRUE(d.is_new);
  EXPECT_DOUBLE_EQ(d.stamp_s, 5.05);
}

TEST(SourceArbiter, MonoWithoutOrientationOrNonFiniteRangeIsUnusable) {
  SourceArbiter arbiter{ArbiterConfig{}};
  EstimateSummary no_orientation = good(Source::kMonoVisible, 1.0, 1.0);
  no_orientation.orientation_valid = false;
  ASSERT_TRUE(arbiter.offer(no_orientation).accepted);
  EstimateSummary nan_range = good(Source::kMonoIr, 1.0, NAN);
  ASSERT_TRUE(arbiter.offer(nan_range).accepted);
  const Decision d = arbiter.decide(1.01);
  EXPECT_FALSE(d.valid);
  EXPECT_NE(d.reason.find("no orientation"), std::string::npos) << d.reason;
  EXPECT_NE(d.reason.find("range is not finite"), std::string::npos) << d.reason;
}

TEST(SourceArbiter, NanPoseMakesTheSourceUnusable) {
  SourceArbiter arbiter{ArbiterConfig{}};
  EstimateSummary nan_pose = good(Source::kMonoVisible, 1.0, 1.0);
  nan_pose.values_finite = false;
  ASSERT_TRUE(arbiter.offer(nan_pose).accepted);
  ASSERT_TRUE(arbiter.offer(good(Source::kMonoIr, 1.0, 1.0)).accepted);
  const Decision d = arbiter.decide(1.01);
  ASSERT_TRUE(d.valid);
  EXPECT_EQ(d.source, Source::kMonoIr);
  EXPECT_NE(d.reason.find("NaN"), std::string::npos) << d.reason;
}

TEST(SourceArbiter, ReconfigureMovesTheSwitchRangeAndRefusesInvalidValues) {
  SourceArbiter arbiter{ArbiterConfig{}};
  EXPECT_EQ(offerAll(arbiter, 1.0, 2.5).source, Source::kDisparity);
  ArbiterConfig wider;
  wider.switch_range_m = 3.0;
  arbiter.reconfigure(wider);
  EXPECT_EQ(offerAll(arbiter, 1.1, 2.5).source, Source::kMonoVisible);  // 2.5 < 3.0 - 0.2
  ArbiterConfig bad = wider;
  bad.hysteresis_m = 5.0;
  EXPECT_THROW(arbiter.reconfigure(bad), std::invalid_argument);
  EXPECT_DOUBLE_EQ(arbiter.config().hysteresis_m, 0.2);  // the old one is kept
}

TEST(SourceArbiter, DisparityIsNeverUsedInsideTheMinimumRange) {
  ArbiterConfig c;
  c.min_disparity_range_m = 0.9;
  SourceArbiter arbiter{c};
  // Far and near the limit: disparity is used (far regime; near regime as the only usable source).
  EXPECT_EQ(offerAll(arbiter, 1.0, 3.0).source, Source::kDisparity);
  ASSERT_TRUE(arbiter.offer(lost(Source::kMonoVisible, 1.1)).accepted);
  ASSERT_TRUE(arbiter.offer(lost(Source::kMonoIr, 1.1)).accepted);
  ASSERT_TRUE(arbiter.offer(good(Source::kDisparity, 1.1, 1.0)).accepted);
  Decision d = arbiter.decide(1.11);
  ASSERT_TRUE(d.valid);
  EXPECT_EQ(d.source, Source::kDisparity);
  // Inside the limit, with the mono poses lost: nothing is usable, and the reason says why.
  ASSERT_TRUE(arbiter.offer(lost(Source::kMonoVisible, 1.2)).accepted);
  ASSERT_TRUE(arbiter.offer(lost(Source::kMonoIr, 1.2)).accepted);
  ASSERT_TRUE(arbiter.offer(good(Source::kDisparity, 1.2, 0.6)).accepted);
  d = arbiter.decide(1.21);
  EXPECT_FALSE(d.valid);
  EXPECT_NE(d.reason.find("disparity too near"), std::string::npos) << d.reason;
  // A mono pose at that range is used.
  ASSERT_TRUE(arbiter.offer(good(Source::kMonoIr, 1.3, 0.6)).accepted);
  ASSERT_TRUE(arbiter.offer(good(Source::kDisparity, 1.3, 0.6)).accepted);
  d = arbiter.decide(1.31);
  ASSERT_TRUE(d.valid);
  EXPECT_EQ(d.source, Source::kMonoIr);
}

TEST(SourceArbiter, VisibleAndIrHaveTheirOwnInlierThresholds) {
  ArbiterConfig c;
  c.min_visible_inliers = 12;
  c.min_ir_inliers = 5;
  SourceArbiter arbiter{c};
  // Five inliers: enough for the IR pose (its five LEDs), too few for the visible one.
  EstimateSummary visible = good(Source::kMonoVisible, 1.0, 1.0);
  visible.feature_inliers = 5;
  EstimateSummary ir = good(Source::kMonoIr, 1.0, 1.0);
  ir.feature_inliers = 5;
  ASSERT_TRUE(arbiter.offer(visible).accepted);
  ASSERT_TRUE(arbiter.offer(ir).accepted);
  Decision d = arbiter.decide(1.01);
  ASSERT_TRUE(d.valid);
  EXPECT_EQ(d.source, Source::kMonoIr);
  EXPECT_NE(d.reason.find("5 inliers < 12"), std::string::npos) << d.reason;
  // Four IR inliers: poor too; nothing usable.
  visible.stamp_s = ir.stamp_s = 1.1;
  ir.feature_inliers = 4;
  ASSERT_TRUE(arbiter.offer(visible).accepted);
  ASSERT_TRUE(arbiter.offer(ir).accepted);
  d = arbiter.decide(1.11);
  EXPECT_FALSE(d.valid);
  EXPECT_NE(d.reason.find("4 inliers < 5"), std::string::npos) << d.reason;
}
