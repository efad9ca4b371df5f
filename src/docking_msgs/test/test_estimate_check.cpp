// The shared estimate checks: each bad input gives its own code; good ones pass.
#include <gtest/gtest.h>

#include <cmath>
#include <limits>

#include "docking_msgs/estimate_check.h"

namespace docking_msgs {
namespace checks {
namespace {

constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();
constexpr double kInf = std::numeric_limits<double>::infinity();

EstimateFields goodFullPose() {
  EstimateFields f;
  f.valid = f.position_valid = f.orientation_valid = f.twist_valid = true;
  f.position = {0.1, -0.2, 1.5};
  f.orientation_xyzw = {0.0, 0.0, std::sin(0.3), std::cos(0.3)};
  for (std::size_t i = 0; i < 6; ++i) {
    f.pose_covariance[i * 6 + i] = 1e-4;
    f.twist_covariance[i * 6 + i] = 1e-2;
  }
  f.pose_covariance[1] = f.pose_covariance[6] = 2e-5;  // symmetric off-diagonal
  f.twist = {0.01, 0.0, 0.0, 0.0, 0.0, 0.02};
  f.range_m = 1.52;
  return f;
}

TEST(StampCheck, EachKindHasItsCode) {
  const StampLimits limits;  // 0.5 s ahead, 5 s old
  EXPECT_EQ(checkStamp(100.0, 100.0, limits), StampProblem::kNone);
  EXPECT_EQ(checkStamp(100.4, 100.0, limits), StampProblem::kNone);
  EXPECT_EQ(checkStamp(96.0, 100.0, limits), StampProblem::kNone);
  EXPECT_EQ(checkStamp(1100.0, 100.0, limits), StampProblem::kFuture);
  EXPECT_EQ(checkStamp(100.6, 100.0, limits), StampProblem::kFuture);
  EXPECT_EQ(checkStamp(94.0, 100.0, limits), StampProblem::kTooOld);
  EXPECT_EQ(checkStamp(0.0, 100.0, limits), StampProblem::kUnset);
  EXPECT_EQ(checkStamp(0.0, 3.0, limits), StampProblem::kUnset);  // issue 53: passed while the sim clock was < 5 s
  EXPECT_EQ(checkStamp(0.5, 3.0, limits), StampProblem::kNone);
  EXPECT_EQ(checkStamp(kNaN, 100.0, limits), StampProblem::kNotFinite);
  EXPECT_EQ(checkStamp(kInf, 100.0, limits), StampProblem::kNotFinite);
  EXPECT_STREQ(stampProblemName(StampProblem::kFuture), "stamp_in_future");
}

TEST(EstimateCheck, GoodEstimatesPass) {
  EXPECT_EQ(checkEstimateFields(goodFullPose()), EstimateProblem::kNone);
  EstimateFields position_only = goodFullPose();
  position_only.orientation_valid = false;
  position_only.orientation_xyzw = {0.0, 0.0, 0.0, 0.0};  // not claimed: not checked
  position_only.pose_covariance[21] = 1e6;                // "not estimated" variance
  EXPECT_EQ(checkEstimateFields(position_only), EstimateProblem::kNone);
}

TEST(EstimateCheck, InvalidEstimateNumbersAreNotChecked) {
  EstimateFields f = goodFullPose();
  f.valid = false;
  f.position = {kNaN, kNaN, kNaN};
  f.orientation_xyzw = {0.0, 0.0, 0.0, 0.0};
  EXPECT_EQ(checkEstimateFields(f), EstimateProblem::kNone);
}

TEST(EstimateCheck, ZeroAndNonUnitQuaternionsAreRefused) {
  EstimateFields f = goodFullPose();
  f.orientation_xyzw = {0.0, 0.0, 0.0, 0.0};
  EXPECT_EQ(checkEstimateFields(f), EstimateProblem::kOrientationNotUnit);
  f.orientation_xyzw = {0.0, 0.0, 0.0, 1.02};
  EXPECT_EQ(checkEstimateFields(f), EstimateProblem::kOrientationNotUnit);
  f.orientation_xyzw = {0.0, 0.0, 0.0, 1.005};  // within the tolerance
  EXPECT_EQ(checkEstimateFields(f), EstimateProblem::kNone);
  f.orientation_xyzw = {0.0, kNaN, 0.0, 1.0};
  EXPECT_EQ(checkEstimateFields(f), EstimateProblem::kOrientationNotFinite);
}

TEST(EstimateCheck, EachNumericProblemHasItsCode) {
  EstimateFields f = goodFullPose();
  f.position[2] = kInf;
  EXPECT_EQ(checkEstimateFields(f), EstimateProblem::kPositionNotFinite);

  f = goodFullPose();
  f.pose_covariance[14] = kNaN;
  EXPECT_EQ(checkEstimateFields(f), EstimateProblem::kPoseCovarianceNotFinite);
  f = goodFullPose();
  f.pose_covariance[1] = 0.5;  // (0, 1) != (1, 0)
  EXPECT_EQ(checkEstimateFields(f), EstimateProblem::kPoseCovarianceNotSymmetric);
  f = goodFullPose();
  f.pose_covariance[7] = -1e-4;
  EXPECT_EQ(checkEstimateFields(f), EstimateProblem::kPoseCovarianceNegativeVariance);

  f = goodFullPose();
  f.range_m = kNaN;
  EXPECT_EQ(checkEstimateFields(f), EstimateProblem::kRangeNotFinite);

  f = goodFullPose();
  f.twist[5] = kNaN;
  EXPECT_EQ(checkEstimateFields(f), EstimateProblem::kTwistNotFinite);
  f = goodFullPose();
  f.twist_covariance[35] = kInf;
  EXPECT_EQ(checkEstimateFields(f), EstimateProblem::kTwistCovarianceNotFinite);
  f = goodFullPose();
  f.twist_covariance[5] = 1.0;
  EXPECT_EQ(checkEstimateFields(f), EstimateProblem::kTwistCovarianceNotSymmetric);
  f = goodFullPose();
  f.twist_covariance[0] = -1.0;
  EXPECT_EQ(checkEstimateFields(f), EstimateProblem::kTwistCovarianceNegativeVariance);
  f.twist_valid = false;  // a twist not claimed is not checked
  EXPECT_EQ(checkEstimateFields(f), EstimateProblem::kNone);
}

TEST(EstimateCheck, EveryEstimateNeedsAFrame) {
  EstimateFields f = goodFullPose();
  f.has_frame_id = false;
  EXPECT_EQ(checkEstimateFields(f), EstimateProblem::kNoFrameId);
  f.valid = false;  // even one that claims nothing: the planner would ask tf2 for an empty frame
  EXPECT_EQ(checkEstimateFields(f), EstimateProblem::kNoFrameId);
  EXPECT_STREQ(estimateProblemName(EstimateProblem::kNoFrameId), "no_frame_id");
}

TEST(EstimateCheck, SymmetryToleranceIsRelative) {
  EstimateFields f = goodFullPose();
  f.pose_covariance[1] = 1e6;
  f.pose_covariance[6] = 1e6 + 1e-4;  // rounding of a rotated 1e6 variance
  EXPECT_EQ(checkEstimateFields(f), EstimateProblem::kNone);
}

TEST(ClockJump, BackwardJumpIsReportedOnce) {
  ClockJumpDetector clock;
  EXPECT_FALSE(clock.jumpedBack(100.0));
  EXPECT_FALSE(clock.jumpedBack(101.0));
  EXPECT_FALSE(clock.jumpedBack(100.8));  // a small step back: not a jump
  EXPECT_TRUE(clock.jumpedBack(3.0));     // sim time reset
  EXPECT_FALSE(clock.jumpedBack(3.1));
  EXPECT_FALSE(clock.jumpedBack(4.0));
}

OdometryFields goodOdometry() {
  OdometryFields f;
  f.position = {3.0, -2.0, 0.0};
  f.orientation_xyzw = {0.0, 0.0, std::sin(0.3), std::cos(0.3)};
  f.twist = {0.3, -0.1, 0.0, 0.0, 0.0, 0.5};
  return f;
}

TEST(OdometryCheck, ATrueRobotPasses) { EXPECT_EQ(checkOdometryFields(goodOdometry()), OdometryProblem::kNone); }

TEST(OdometryCheck, EachProblemIsNamedByItsCode) {
  OdometryFields f = goodOdometry();
  f.position[1] = std::numeric_limits<double>::quiet_NaN();
  EXPECT_EQ(checkOdometryFields(f), OdometryProblem::kPositionNotFinite);
  f = goodOdometry();
  f.position[0] = 1e30;  // huge but finite: what poisoned the planner's history (issue 12)
  EXPECT_EQ(checkOdometryFields(f), OdometryProblem::kPositionOutOfBounds);
  f = goodOdometry();
  f.orientation_xyzw[3] = std::numeric_limits<double>::infinity();
  EXPECT_EQ(checkOdometryFields(f), OdometryProblem::kOrientationNotFinite);
  f = goodOdometry();
  f.orientation_xyzw = {0.0, 0.0, 0.0, 0.0};
  EXPECT_EQ(checkOdometryFields(f), OdometryProblem::kOrientationNotUnit);
  f = goodOdometry();
  f.twist[5] = std::numeric_limits<double>::quiet_NaN();
  EXPECT_EQ(checkOdometryFields(f), OdometryProblem::kTwistNotFinite);
  f = goodOdometry();
  f.twist[0] = 1e6;
  EXPECT_EQ(checkOdometryFields(f), OdometryProblem::kTwistOutOfBounds);
  f = goodOdometry();
  f.twist[5] = -1e3;
  EXPECT_EQ(checkOdometryFields(f), OdometryProblem::kTwistOutOfBounds);
}

TEST(OdometryCheck, BoundsAreInclusiveOfTheLimits) {
  OdometryFields f = goodOdometry();
  f.position[0] = kMaxOdometryPositionM;
  f.twist[0] = kMaxOdometrySpeedMps;
  f.twist[1] = 0.0;
  f.twist[5] = kMaxOdometryTurnRateRadps;
  EXPECT_EQ(checkOdometryFields(f), OdometryProblem::kNone);
  f.position[0] = std::nextafter(kMaxOdometryPositionM, 2 * kMaxOdometryPositionM);
  EXPECT_EQ(checkOdometryFields(f), OdometryProblem::kPositionOutOfBounds);
}

}  // namespace
}  // namespace checks
}  // namespace docking_msgs
