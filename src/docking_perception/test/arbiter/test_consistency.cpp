#include <gtest/gtest.h>

#include <cmath>
#include <stdexcept>

#include "docking_perception/arbiter/consistency.h"

using docking_perception::arbiter::ComparablePose;
using docking_perception::arbiter::compare;
using docking_perception::arbiter::ConsistencyConfig;
using docking_perception::arbiter::Matrix6d;

namespace {

constexpr double kDeg = M_PI / 180.0;

ComparablePose pose(double stamp, const Eigen::Vector3d& position, double sigma_m, double sigma_rad,
                    bool has_orientation = true) {
  ComparablePose p;
  p.stamp_s = stamp;
  p.pose.position = position;
  p.pose.orientation = Eigen::Quaterniond(Eigen::AngleAxisd(0.3, Eigen::Vector3d::UnitY()));
  p.pose.covariance = Matrix6d::Zero();
  p.pose.covariance.diagonal() << Eigen::Vector3d::Constant(sigma_m * sigma_m),
      Eigen::Vector3d::Constant(sigma_rad * sigma_rad);
  p.has_orientation = has_orientation;
  return p;
}

}  // namespace

TEST(Consistency, IdenticalPosesAgreeWithChi2Zero) {
  const ComparablePose a = pose(1.0, {0.1, 0.0, 1.0}, 0.01, 0.01);
  const auto test = compare(a, a, ConsistencyConfig{});
  ASSERT_TRUE(test);
  EXPECT_EQ(test->dof, 6);
  EXPECT_NEAR(test->chi2, 0.0, 1e-12);
  EXPECT_TRUE(test->agree);
}

TEST(Consistency, PositionDifferenceIsWeighedByBothCovariancesAndTheMountSigma) {
  ConsistencyConfig c;
  const ComparablePose a = pose(1.0, {0.0, 0.0, 1.0}, 0.01, 0.01);
  const ComparablePose b = pose(1.0, {0.03, 0.0, 1.0}, 0.01, 0.01);
  const auto test = compare(a, b, c);
  ASSERT_TRUE(test);
  const double variance = 2 * 0.01 * 0.01 + c.mount_sigma_m * c.mount_sigma_m;  // dt = 0: no motion term
  EXPECT_NEAR(test->chi2, 0.03 * 0.03 / variance, 1e-9);
  EXPECT_EQ(test->dof, 6);
  EXPECT_NEAR(test->gate, 22.458, 0.001);  // the 99.9 % point of chi-square, 6 dof
  EXPECT_EQ(test->agree, test->chi2 <= test->gate);
}

TEST(Consistency, OrientationDifferenceUsesTheShortestRotationWhateverTheQuaternionSign) {
  ConsistencyConfig c;
  const ComparablePose a = pose(1.0, {0.0, 0.0, 1.0}, 0.005, 0.5 * kDeg);
  ComparablePose b = a;
  b.pose.orientation = Eigen::Quaterniond(Eigen::AngleAxisd(15 * kDeg, Eigen::Vector3d::UnitX())) * a.pose.orientation;
  b.pose.orientation.coeffs() *= -1.0;  // the same rotation
  const auto test = compare(a, b, c);
  ASSERT_TRUE(test);
  const double variance = 2 * std::pow(0.5 * kDeg, 2) + c.mount_sigma_rad * c.mount_sigma_rad;
  EXPECT_NEAR(test->chi2, std::pow(15 * kDeg, 2) / variance, 1e-6);
  EXPECT_FALSE(test->agree);

  ComparablePose same = a;
  same.pose.orientation.coeffs() *= -1.0;
  EXPECT_NEAR(compare(a, same, c)->chi2, 0.0, 1e-12);
}

TEST(Consistency, WithoutOrientationOnlyPositionIsCompared) {
  ConsistencyConfig c;
  const ComparablePose mono = pose(1.0, {0.0, 0.0, 3.0}, 0.01, 0.5 * kDeg);
  ComparablePose disparity = pose(1.0, {0.0, 0.0, 3.0}, 0.05, 0.0, false);
  disparity.pose.orientation = Eigen::Quaterniond(Eigen::AngleAxisd(M_PI / 2, Eigen::Vector3d::UnitZ()));
  disparity.pose.covariance.bottomRightCorner<3, 3>() = Eigen::Matrix3d::Identity() * 1e6;  // unknown
  auto test = compare(mono, disparity, c);
  ASSERT_TRUE(test);
  EXPECT_EQ(test->dof, 3);
  EXPECT_NEAR(test->chi2, 0.0, 1e-12);
  EXPECT_NEAR(test->gate, 16.266, 0.001);  // the 99.9 % point of chi-square, 3 dof

  disparity.pose.position.x() = 1.8;  // a background object beside the target
  test = compare(mono, disparity, c);
  ASSERT_TRUE(test);
  EXPECT_FALSE(test->agree);
}

TEST(Consistency, StampDifferenceAllowsTheEstimatedMotionOrTheFloor) {
  ConsistencyConfig c;
  const ComparablePose a = pose(1.00, {0.0, 0.0, 1.0}, 0.001, 0.002);
  const ComparablePose b = pose(1.04, {0.03, 0.0, 1.0}, 0.001, 0.002);  // 3 cm in 40 ms
  auto test = compare(a, b, c);
  ASSERT_TRUE(test);
  EXPECT_NEAR(test->dt_s, 0.04, 1e-12);
  EXPECT_FALSE(test->agree) << test->chi2;  // 3 cm is far more than the floor's 2 mm

  ComparablePose moving = b;
  moving.speed_mps = 0.75;  // 3 cm in 40 ms: that is the motion
  test = compare(a, moving, c);
  ASSERT_TRUE(test);
  EXPECT_TRUE(test->agree) << test->chi2;
}

TEST(Consistency, ZeroCovariancesStayDefinedAndNonFiniteOnesAreNotCompared) {
  ConsistencyConfig c;
  const ComparablePose a = pose(1.0, {0.0, 0.0, 1.0}, 0.0, 0.0);
  const ComparablePose b = pose(1.0, {0.001, 0.0, 1.0}, 0.0, 0.0);
  const auto test = compare(a, b, c);
  ASSERT_TRUE(test);
  EXPECT_TRUE(std::isfinite(test->chi2));

  ComparablePose broken = b;
  broken.pose.covariance(0, 0) = NAN;
  EXPECT_FALSE(compare(a, broken, c));
  broken = b;
  broken.pose.position.x() = INFINITY;
  EXPECT_FALSE(compare(a, broken, c));
}

TEST(Consistency, RejectsInvalidConfiguration) {
  EXPECT_NO_THROW(validate(ConsistencyConfig{}));
  ConsistencyConfig c;
  c.gate_probability = 1.0;  // no gate at all: refused
  EXPECT_THROW(validate(c), std::invalid_argument);
  c = ConsistencyConfig{};
  c.stamp_tolerance_s = -0.01;
  EXPECT_THROW(validate(c), std::invalid_argument);
  c = ConsistencyConfig{};
  c.mount_sigma_rad = 0.0;
  EXPECT_THROW(validate(c), std::invalid_argument);
  c = ConsistencyConfig{};
  c.mount_sigma_m = NAN;
  try {
    validate(c);
    FAIL() << "no exception";
  } catch (const docking_settings::ConfigError& e) {
    EXPECT_EQ(e.key(), "mount_sigma_m");  // the node's loader names it with its prefix, consistency_
    EXPECT_EQ(e.problem(), docking_settings::ConfigProblem::kOutOfRange);
  }
}
