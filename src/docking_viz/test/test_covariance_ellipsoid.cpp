// covarianceEllipsoid: axes and 3-sigma lengths of known covariances; unusable ones refused.
#include <gtest/gtest.h>

#include <Eigen/Geometry>
#include <cmath>
#include <limits>

#include "docking_viz/covariance_ellipsoid.h"

using namespace docking_viz;

namespace {

// The ellipsoid's axis that is parallel (either sign) to `direction`, as an index; -1 when none is.
int axisAlong(const Ellipsoid& e, const Eigen::Vector3d& direction) {
  const Eigen::Matrix3d axes = e.orientation.toRotationMatrix();
  for (int i = 0; i < 3; ++i) {
    if (std::abs(std::abs(axes.col(i).dot(direction.normalized())) - 1.0) < 1e-9) return i;
  }
  return -1;
}

}  // namespace

TEST(CovarianceEllipsoid, DiagonalGivesTheFrameAxesAndThreeSigma) {
  const Eigen::Vector3d sigmas(0.02, 0.05, 0.01);  // m
  const EllipsoidResult r = covarianceEllipsoid(sigmas.cwiseAbs2().asDiagonal().toDenseMatrix());
  ASSERT_TRUE(r.valid()) << ellipsoidProblemName(r.problem);
  for (int frame_axis = 0; frame_axis < 3; ++frame_axis) {
    const int i = axisAlong(r.ellipsoid, Eigen::Vector3d::Unit(frame_axis));
    ASSERT_GE(i, 0) << "no ellipsoid axis along frame axis " << frame_axis;
    EXPECT_NEAR(r.ellipsoid.semi_axes_m(i), 3.0 * sigmas(frame_axis), 1e-12);
  }
  // A proper rotation, not a mirror.
  EXPECT_NEAR(r.ellipsoid.orientation.toRotationMatrix().determinant(), 1.0, 1e-12);
}

TEST(CovarianceEllipsoid, RotatedCovarianceGivesTheRotatedAxes) {
  const Eigen::Matrix3d rotation =
      (Eigen::AngleAxisd(0.7, Eigen::Vector3d::UnitZ()) * Eigen::AngleAxisd(-0.4, Eigen::Vector3d::UnitX())).toRotationMatrix();
  const Eigen::Vector3d variances(0.0004, 0.0025, 0.0001);  // sigmas 2 cm, 5 cm, 1 cm along the rotated axes
  const Eigen::Matrix3d covariance = rotation * variances.asDiagonal() * rotation.transpose();
  const EllipsoidResult r = covarianceEllipsoid(covariance, 2.0);
  ASSERT_TRUE(r.valid()) << ellipsoidProblemName(r.problem);
  for (int k = 0; k < 3; ++k) {
    const int i = axisAlong(r.ellipsoid, rotation.col(k));
    ASSERT_GE(i, 0) << "no ellipsoid axis along rotated axis " << k;
    EXPECT_NEAR(r.ellipsoid.semi_axes_m(i), 2.0 * std::sqrt(variances(k)), 1e-9);
  }
  // The longest axis is the 5 cm one, whichever order the solver returns.
  EXPECT_NEAR(r.ellipsoid.semi_axes_m.maxCoeff(), 0.1, 1e-9);
}

TEST(CovarianceEllipsoid, RefusesNanAndInfinity) {
  Eigen::Matrix3d c = Eigen::Matrix3d::Identity() * 0.01;
  c(1, 2) = c(2, 1) = std::numeric_limits<double>::quiet_NaN();
  EXPECT_EQ(covarianceEllipsoid(c).problem, EllipsoidProblem::kNotFinite);
  c = Eigen::Matrix3d::Identity() * 0.01;
  c(0, 0) = std::numeric_limits<double>::infinity();
  EXPECT_EQ(covarianceEllipsoid(c).problem, EllipsoidProblem::kNotFinite);
  EXPECT_EQ(covarianceEllipsoid(Eigen::Matrix3d::Identity() * 0.01, std::nan("")).problem, EllipsoidProblem::kNotFinite);
  EXPECT_EQ(covarianceEllipsoid(Eigen::Matrix3d::Identity() * 0.01, 0.0).problem, EllipsoidProblem::kNotFinite);
}

TEST(CovarianceEllipsoid, RefusesDegenerateAndIndefinite) {
  EXPECT_EQ(covarianceEllipsoid(Eigen::Matrix3d::Zero()).problem, EllipsoidProblem::kNotPositiveDefinite);
  // Rank 2: flat in z.
  EXPECT_EQ(covarianceEllipsoid(Eigen::Vector3d(0.01, 0.01, 0.0).asDiagonal().toDenseMatrix()).problem,
            EllipsoidProblem::kNotPositiveDefinite);
  // Positive diagonal, but indefinite: correlation above 1 (eigenvalues 0.01 +- 0.02).
  Eigen::Matrix3d c = Eigen::Matrix3d::Identity() * 0.01;
  c(0, 1) = c(1, 0) = 0.02;
  EXPECT_EQ(covarianceEllipsoid(c).problem, EllipsoidProblem::kNotPositiveDefinite);
}

TEST(CovarianceEllipsoid, RefusesAsymmetricAndUnknownVariance) {
  Eigen::Matrix3d c = Eigen::Matrix3d::Identity() * 0.01;
  c(0, 1) = 0.001;
  EXPECT_EQ(covarianceEllipsoid(c).problem, EllipsoidProblem::kNotSymmetric);
  // TargetEstimate's "not valid" variance: a 3 km ellipsoid is not a shape to draw.
  EXPECT_EQ(covarianceEllipsoid(Eigen::Vector3d(0.01, 0.01, kUnknownVariance).asDiagonal().toDenseMatrix()).problem,
            EllipsoidProblem::kUnknownVariance);
}

TEST(CovarianceEllipsoid, PositionBlockOfARowMajorPoseCovariance) {
  double pose[36] = {};
  for (int i = 0; i < 36; ++i) pose[i] = 100.0 + i;
  const Eigen::Matrix3d m = positionCovariance(pose);
  EXPECT_EQ(m(0, 0), 100.0);
  EXPECT_EQ(m(0, 2), 102.0);
  EXPECT_EQ(m(1, 0), 106.0);  // row 1 starts at index 6
  EXPECT_EQ(m(2, 2), 114.0);
}
