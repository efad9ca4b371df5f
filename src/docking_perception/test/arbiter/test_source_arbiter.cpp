#include <gtest/gtest.h>

#include <cmath>
#include <stdexcept>

#include "docking_perception/arbiter/source_arbiter.h"

using docking_perception::arbiter::ArbiterConfig;
using docking_perception::arbiter::Decision;
using docking_perception::arbiter::OfferProblem;
using docking_perception::arbiter::OfferResult;
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

  EstimateSummary broken = good(Source::kMonoVisible, 1.1, 1.0);
  broken.reprojection_error_px = NAN;  // a pose whose residual is not a number
  ASSERT_TRUE(arbiter.offer(broken).accepted);
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

TEST(SourceArbiter, NonFiniteRangeIsUnusable) {
  SourceArbiter arbiter{ArbiterConfig{}};
  EstimateSummary nan_range = good(Source::kMonoIr, 1.0, NAN);
  ASSERT_TRUE(arbiter.offer(nan_range).accepted);
  const Decision d = arbiter.decide(1.01);
  EXPECT_FALSE(d.valid);
  EXPECT_NE(d.reason.find("range is not finite"), std::string::npos) << d.reason;
}

// A mono pose whose orientation is withheld (rotation sigma too large) still gives a position; the
// other mono source, claiming an orientation, goes first.
TEST(SourceArbiter, MonoWithoutOrientationIsPositionOnlyAfterOneWithOrientation) {
  SourceArbiter arbiter{ArbiterConfig{}};
  EstimateSummary no_orientation = good(Source::kMonoVisible, 1.0, 1.0);
  no_orientation.orientation_valid = false;
  ASSERT_TRUE(arbiter.offer(no_orientation).accepted);
  Decision d = arbiter.decide(1.01);
  ASSERT_TRUE(d.valid) << d.reason;
  EXPECT_EQ(d.source, Source::kMonoVisible);

  ASSERT_TRUE(arbiter.offer(good(Source::kMonoIr, 1.02, 1.0)).accepted);
  no_orientation.stamp_s = 1.02;
  ASSERT_TRUE(arbiter.offer(no_orientation).accepted);
  d = arbiter.decide(1.03);
  ASSERT_TRUE(d.valid) << d.reason;
  EXPECT_EQ(d.source, Source::kMonoIr);
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

TEST(SourceArbiter, OnlyTheVisiblePoseHasAnInlierThreshold) {
  ArbiterConfig c;
  c.min_visible_inliers = 12;
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
  // Twelve visible inliers: the visible pose is usable again and, nearer in the preference, chosen.
  visible.stamp_s = ir.stamp_s = 1.1;
  visible.feature_inliers = 12;
  ASSERT_TRUE(arbiter.offer(visible).accepted);
  ASSERT_TRUE(arbiter.offer(ir).accepted);
  d = arbiter.decide(1.11);
  ASSERT_TRUE(d.valid);
  EXPECT_EQ(d.source, Source::kMonoVisible) << d.reason;
}

// ---- Consistency across sources ------------------------------------------------------------------

using docking_perception::arbiter::DecisionCode;
using docking_perception::arbiter::Matrix6d;
using docking_perception::arbiter::PoseWithCovariance3;
using docking_perception::arbiter::Resolution;

namespace {

constexpr double kDeg = M_PI / 180.0;

// The target `range` m ahead of the camera, turned `yaw_deg` about the camera's y axis, `offset_x`
// to the side, with the given 1-sigma position and orientation uncertainty (common frame).
EstimateSummary posed(Source source, double stamp, double range, double yaw_deg, double sigma_m, double sigma_deg,
                      double offset_x = 0.0) {
  EstimateSummary e = good(source, stamp, range);
  PoseWithCovariance3 p;
  p.position = Eigen::Vector3d(offset_x, 0.0, range);
  p.orientation = Eigen::Quaterniond(Eigen::AngleAxisd(M_PI + yaw_deg * kDeg, Eigen::Vector3d::UnitY()));
  p.covariance = Matrix6d::Zero();
  p.covariance.diagonal() << Eigen::Vector3d::Constant(sigma_m * sigma_m),
      Eigen::Vector3d::Constant(std::pow(sigma_deg * kDeg, 2));
  if (source == Source::kDisparity) p.covariance.bottomRightCorner<3, 3>().diagonal().setConstant(1e6);
  e.pose = p;
  return e;
}

}  // namespace

TEST(SourceArbiterConsistency, AgreeingSourcesPassUnchanged) {
  ArbiterConfig off;
  off.consistency.enabled = false;
  SourceArbiter checked{ArbiterConfig{}};
  SourceArbiter unchecked{off};
  double t = 1.0;
  for (int i = 0; i < 20; ++i, t += 0.033) {
    // Small differences, well inside the sources' own sigmas (fixed, not random).
    const double wobble = std::sin(0.9 * i);
    const double range = 1.0 + 0.05 * i;  // approaching from 2 m to 1 m and beyond: near and far regime
    for (SourceArbiter* a : {&checked, &unchecked}) {
      ASSERT_TRUE(a->offer(posed(Source::kMonoVisible, t, range, 0.3 * wobble, 0.004, 0.5)).accepted);
      ASSERT_TRUE(a->offer(posed(Source::kMonoIr, t + 0.01, range + 0.003 * wobble, -0.4 * wobble, 0.006, 1.0)).accepted);
      ASSERT_TRUE(a->offer(posed(Source::kDisparity, t, range - 0.02 * wobble, 0.0, 0.03, 0.0)).accepted);
    }
    const Decision d = checked.decide(t + 0.02);
    const Decision reference = unchecked.decide(t + 0.02);
    ASSERT_TRUE(d.valid) << d.reason;
    EXPECT_EQ(d.code, DecisionCode::kChosen) << d.reason;
    EXPECT_EQ(d.source, reference.source) << "i=" << i;
    EXPECT_EQ(d.reason, reference.reason) << "i=" << i;
    EXPECT_EQ(d.is_new, reference.is_new);
  }
  // Each frame, the chosen source against the two others.
  EXPECT_EQ(checked.consistencyCounts().comparisons, 40u);
  EXPECT_EQ(checked.consistencyCounts().disagreements, 0u);
}

TEST(SourceArbiterConsistency, ConfidentlyWrongVisibleIsRejectedForIrBackedByThePreviousOutput) {
  SourceArbiter arbiter{ArbiterConfig{}};
  // Frame 1: both mono poses agree; the visible one is published (preferred near).
  ASSERT_TRUE(arbiter.offer(posed(Source::kMonoVisible, 1.000, 1.0, 0.0, 0.003, 0.5)).accepted);
  ASSERT_TRUE(arbiter.offer(posed(Source::kMonoIr, 1.005, 1.0, 0.2, 0.004, 1.0)).accepted);
  Decision d = arbiter.decide(1.01);
  ASSERT_TRUE(d.valid);
  EXPECT_EQ(d.source, Source::kMonoVisible);
  EXPECT_TRUE(d.is_new);
  // Frame 2: glare turns the visible pose 15 deg, still with a 0.5 deg sigma; IR stays put.
  ASSERT_TRUE(arbiter.offer(posed(Source::kMonoVisible, 1.033, 1.0, 15.0, 0.003, 0.5)).accepted);
  ASSERT_TRUE(arbiter.offer(posed(Source::kMonoIr, 1.038, 1.0, 0.1, 0.004, 1.0)).accepted);
  d = arbiter.decide(1.04);
  ASSERT_TRUE(d.valid) << d.reason;
  EXPECT_EQ(d.source, Source::kMonoIr) << d.reason;
  EXPECT_TRUE(d.is_new);
  EXPECT_EQ(d.code, DecisionCode::kChosenOverDisagreement);
  EXPECT_EQ(d.resolution, Resolution::kPreviousOutput);
  EXPECT_TRUE(d.inconsistent[static_cast<std::size_t>(Source::kMonoVisible)]);
  EXPECT_FALSE(d.inconsistent[static_cast<std::size_t>(Source::kMonoIr)]);
  EXPECT_EQ(arbiter.consistencyCounts().disagreements, 1u);
  EXPECT_EQ(arbiter.consistencyCounts().resolved_by_previous_output, 1u);
  // Deciding again on the same estimates counts nothing new.
  arbiter.decide(1.05);
  EXPECT_EQ(arbiter.consistencyCounts().disagreements, 1u);
  // Frame 3: the glare persists; the previous output is now IR's, which still backs IR.
  ASSERT_TRUE(arbiter.offer(posed(Source::kMonoVisible, 1.066, 1.0, 16.0, 0.003, 0.5)).accepted);
  ASSERT_TRUE(arbiter.offer(posed(Source::kMonoIr, 1.071, 1.0, 0.0, 0.004, 1.0)).accepted);
  d = arbiter.decide(1.075);
  ASSERT_TRUE(d.valid);
  EXPECT_EQ(d.source, Source::kMonoIr);
  EXPECT_EQ(arbiter.consistencyCounts().resolved_by_previous_output, 2u);
}

TEST(SourceArbiterConsistency, AThirdSourceOutvotesADisparityBlobBesideTheTarget) {
  SourceArbiter arbiter{ArbiterConfig{}};
  // Far (4 m): disparity preferred, but its blob is a background object 1.8 m to the side; both mono
  // poses see the target where it is. No previous output: the third source decides.
  ASSERT_TRUE(arbiter.offer(posed(Source::kDisparity, 2.0, 4.0, 0.0, 0.05, 0.0, 1.8)).accepted);
  ASSERT_TRUE(arbiter.offer(posed(Source::kMonoVisible, 2.0, 4.0, 0.0, 0.02, 2.0)).accepted);
  ASSERT_TRUE(arbiter.offer(posed(Source::kMonoIr, 2.01, 4.02, 1.0, 0.03, 3.0)).accepted);
  const Decision d = arbiter.decide(2.02);
  ASSERT_TRUE(d.valid) << d.reason;
  EXPECT_EQ(d.regime, RangeRegime::kFar);
  EXPECT_EQ(d.source, Source::kMonoVisible) << d.reason;
  EXPECT_EQ(d.code, DecisionCode::kChosenOverDisagreement);
  EXPECT_EQ(d.resolution, Resolution::kThirdSource);
  EXPECT_TRUE(d.inconsistent[static_cast<std::size_t>(Source::kDisparity)]);
  EXPECT_NE(d.reason.find("disparity contradicts mono_visible"), std::string::npos) << d.reason;
  // Both contradictions of the blob (with mono_visible, and with mono_ir) were decided by the other mono.
  EXPECT_EQ(arbiter.consistencyCounts().disagreements, 2u);
  EXPECT_EQ(arbiter.consistencyCounts().resolved_by_third_source, 2u);
}

TEST(SourceArbiterConsistency, ADisagreementNothingDecidesIsPublishedInvalidWithItsCode) {
  SourceArbiter arbiter{ArbiterConfig{}};
  // No previous output, no third source.
  ASSERT_TRUE(arbiter.offer(posed(Source::kMonoVisible, 1.0, 1.0, 15.0, 0.003, 0.5)).accepted);
  ASSERT_TRUE(arbiter.offer(posed(Source::kMonoIr, 1.0, 1.0, 0.0, 0.004, 1.0)).accepted);
  Decision d = arbiter.decide(1.01);
  EXPECT_FALSE(d.valid);
  EXPECT_EQ(d.code, DecisionCode::kSourcesDisagree);
  EXPECT_TRUE(d.inconsistent[static_cast<std::size_t>(Source::kMonoVisible)]);
  EXPECT_TRUE(d.inconsistent[static_cast<std::size_t>(Source::kMonoIr)]);
  EXPECT_EQ(arbiter.consistencyCounts().undecided, 1u);
  // A disparity position cannot decide an orientation disagreement: still invalid.
  ASSERT_TRUE(arbiter.offer(posed(Source::kDisparity, 1.0, 1.0, 0.0, 0.03, 0.0)).accepted);
  d = arbiter.decide(1.02);
  EXPECT_FALSE(d.valid);
  EXPECT_EQ(d.code, DecisionCode::kSourcesDisagree);
  // Nothing usable at all has its own code.
  d = arbiter.decide(5.0);
  EXPECT_FALSE(d.valid);
  EXPECT_EQ(d.code, DecisionCode::kNoUsableEstimate);
}

TEST(SourceArbiterConsistency, APreviousOutputOlderThanTheTimeoutDecidesNothing) {
  SourceArbiter arbiter{ArbiterConfig{}};  // timeout_s 0.5
  ASSERT_TRUE(arbiter.offer(posed(Source::kMonoIr, 1.0, 1.0, 0.0, 0.004, 1.0)).accepted);
  ASSERT_TRUE(arbiter.decide(1.01).valid);
  ASSERT_TRUE(arbiter.offer(posed(Source::kMonoVisible, 1.6, 1.0, 15.0, 0.003, 0.5)).accepted);
  ASSERT_TRUE(arbiter.offer(posed(Source::kMonoIr, 1.6, 1.0, 0.0, 0.004, 1.0)).accepted);
  const Decision d = arbiter.decide(1.61);
  EXPECT_FALSE(d.valid);
  EXPECT_EQ(d.code, DecisionCode::kSourcesDisagree);
}

TEST(SourceArbiterConsistency, EstimatesFurtherApartThanTheStampToleranceAreNotCompared) {
  ArbiterConfig c;
  c.consistency.stamp_tolerance_s = 0.05;
  SourceArbiter arbiter{c};
  ASSERT_TRUE(arbiter.offer(posed(Source::kMonoIr, 1.0, 1.0, 0.0, 0.004, 1.0)).accepted);
  ASSERT_TRUE(arbiter.offer(posed(Source::kMonoVisible, 1.08, 1.0, 15.0, 0.003, 0.5)).accepted);
  const Decision d = arbiter.decide(1.09);
  ASSERT_TRUE(d.valid);
  EXPECT_EQ(d.source, Source::kMonoVisible);
  EXPECT_EQ(d.code, DecisionCode::kChosen);
  EXPECT_EQ(arbiter.consistencyCounts().comparisons, 0u);
  // The same pair within the tolerance is compared (and, with nothing to decide, refused).
  c.consistency.stamp_tolerance_s = 0.1;
  arbiter.reconfigure(c);
  EXPECT_EQ(arbiter.decide(1.09).code, DecisionCode::kSourcesDisagree);
  EXPECT_EQ(arbiter.consistencyCounts().comparisons, 1u);
}

TEST(SourceArbiterConsistency, HonestlyLargeCovariancesPass) {
  SourceArbiter arbiter{ArbiterConfig{}};
  // The same 15 deg difference, but the visible pose says it is uncertain by 8 deg.
  ASSERT_TRUE(arbiter.offer(posed(Source::kMonoVisible, 1.0, 1.0, 15.0, 0.003, 8.0)).accepted);
  ASSERT_TRUE(arbiter.offer(posed(Source::kMonoIr, 1.0, 1.0, 0.0, 0.004, 1.0)).accepted);
  const Decision d = arbiter.decide(1.01);
  ASSERT_TRUE(d.valid) << d.reason;
  EXPECT_EQ(d.source, Source::kMonoVisible);
  EXPECT_EQ(d.code, DecisionCode::kChosen);
  EXPECT_EQ(arbiter.consistencyCounts().comparisons, 1u);
  EXPECT_EQ(arbiter.consistencyCounts().disagreements, 0u);
}

TEST(SourceArbiterConsistency, DisabledCheckKeepsTheFormerChoice) {
  ArbiterConfig c;
  c.consistency.enabled = false;
  SourceArbiter arbiter{c};
  ASSERT_TRUE(arbiter.offer(posed(Source::kMonoVisible, 1.0, 1.0, 15.0, 0.003, 0.5)).accepted);
  ASSERT_TRUE(arbiter.offer(posed(Source::kMonoIr, 1.0, 1.0, 0.0, 0.004, 1.0)).accepted);
  const Decision d = arbiter.decide(1.01);
  ASSERT_TRUE(d.valid);
  EXPECT_EQ(d.source, Source::kMonoVisible);
  EXPECT_EQ(arbiter.consistencyCounts().comparisons, 0u);
}

TEST(SourceArbiterConsistency, InvalidConsistencySettingsAreRefused) {
  ArbiterConfig c;
  c.consistency.gate_probability = -1.0;
  EXPECT_THROW(SourceArbiter{c}, std::invalid_argument);
  SourceArbiter arbiter{ArbiterConfig{}};
  EXPECT_THROW(arbiter.reconfigure(c), std::invalid_argument);
  EXPECT_GT(arbiter.config().consistency.gate_probability, 0.0);
}

// Issue 12 item 2: one estimate stamped 1000 s ahead must not become the latest stamp that every later
// estimate of that source is compared against.
TEST(SourceArbiterStamps, FutureStampIsRejectedWithoutTrace) {
  SourceArbiter arbiter{ArbiterConfig{}};
  ASSERT_TRUE(arbiter.offer(good(Source::kMonoVisible, 10.0, 1.0), 10.0).accepted);
  const OfferResult future = arbiter.offer(good(Source::kMonoVisible, 1010.0, 1.0), 10.01);
  EXPECT_FALSE(future.accepted);
  EXPECT_EQ(future.problem, OfferProblem::kStampInFuture);
  EXPECT_DOUBLE_EQ(arbiter.latest(Source::kMonoVisible)->stamp_s, 10.0);
  for (int i = 1; i <= 5; ++i) {
    const double stamp = 10.0 + 0.066 * i;
    const OfferResult next = arbiter.offer(good(Source::kMonoVisible, stamp, 1.0), stamp + 0.02);
    EXPECT_TRUE(next.accepted) << next.reason;
    const Decision d = arbiter.decide(stamp + 0.02);
    EXPECT_TRUE(d.valid && d.is_new) << d.reason;
  }
  // Within the tolerance (0.5 s): accepted (clock skew between computers).
  EXPECT_TRUE(arbiter.offer(good(Source::kMonoVisible, 10.7, 1.0), 10.4).accepted);
}

TEST(SourceArbiterStamps, TooOldAndNonFiniteStampsAreRejected) {
  SourceArbiter arbiter{ArbiterConfig{}};
  const OfferResult old = arbiter.offer(good(Source::kMonoIr, 1.0, 1.0), 100.0);
  EXPECT_FALSE(old.accepted);
  EXPECT_EQ(old.problem, OfferProblem::kStampTooOld);
  EXPECT_FALSE(arbiter.latest(Source::kMonoIr).has_value());
  EXPECT_EQ(arbiter.offer(good(Source::kMonoIr, NAN, 1.0), 100.0).problem, OfferProblem::kStampNotFinite);
  EXPECT_EQ(arbiter.rejectedCount(), 2u);
  // Issue 53: a zero stamp passed while the sim clock was under max_age_s.
  EXPECT_EQ(arbiter.offer(good(Source::kMonoIr, 0.0, 1.0), 3.0).problem, OfferProblem::kStampUnset);
  EXPECT_EQ(arbiter.rejectedCount(), 3u);
  EXPECT_TRUE(arbiter.offer(good(Source::kMonoIr, 99.9, 1.0), 100.0).accepted);
  EXPECT_EQ(arbiter.offer(good(Source::kMonoIr, 99.8, 1.0), 100.0).problem, OfferProblem::kOutOfOrder);
}

TEST(SourceArbiterStamps, ClockJumpBackResetsTheOrdering) {
  SourceArbiter arbiter{ArbiterConfig{}};
  ASSERT_TRUE(arbiter.offer(good(Source::kDisparity, 50.0, 3.0), 50.01).accepted);
  ASSERT_TRUE(arbiter.decide(50.02).is_new);
  // Sim time restarts at 0 (or a bag loops): the new timeline's estimates are accepted and published.
  const OfferResult after = arbiter.offer(good(Source::kDisparity, 1.0, 3.0), 1.01);
  EXPECT_TRUE(after.accepted) << after.reason;
  EXPECT_EQ(arbiter.clockJumpsBack(), 1u);
  const Decision d = arbiter.decide(1.02);
  EXPECT_TRUE(d.valid) << d.reason;
  EXPECT_TRUE(d.is_new);
  EXPECT_DOUBLE_EQ(d.stamp_s, 1.0);
}

