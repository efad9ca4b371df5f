#include "docking_viz/covariance_ellipsoid.h"

#include <Eigen/Eigenvalues>
#include <algorithm>
#include <cmath>

namespace docking_viz {

const char* ellipsoidProblemName(EllipsoidProblem problem) {
  switch (problem) {
    case EllipsoidProblem::kNone: return "none";
    case EllipsoidProblem::kNotFinite: return "not finite";
    case EllipsoidProblem::kNotSymmetric: return "not symmetric";
    case EllipsoidProblem::kNotPositiveDefinite: return "not positive definite";
    case EllipsoidProblem::kUnknownVariance: return "unknown variance";
  }
  return "unknown problem";
}

namespace {

bool symmetric(const Eigen::Matrix3d& m) {
  for (int i = 0; i < 3; ++i) {
    for (int j = i + 1; j < 3; ++j) {
      const double scale = std::max({1.0, std::abs(m(i, j)), std::abs(m(j, i))});
      if (std::abs(m(i, j) - m(j, i)) > kSymmetryTolerance * scale) return false;
    }
  }
  return true;
}

}  // namespace

EllipsoidResult covarianceEllipsoid(const Eigen::Matrix3d& covariance, double sigma_scale) {
  EllipsoidResult result;
  if (!covariance.allFinite() || !std::isfinite(sigma_scale) || sigma_scale <= 0.0) {
    result.problem = EllipsoidProblem::kNotFinite;
    return result;
  }
  if (!symmetric(covariance)) {
    result.problem = EllipsoidProblem::kNotSymmetric;
    return result;
  }
  // Symmetrise the rounding away so that the solver sees an exactly self-adjoint matrix.
  const Eigen::Matrix3d sym = 0.5 * (covariance + covariance.transpose());
  const Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> solver(sym);
  if (solver.info() != Eigen::Success) {
    result.problem = EllipsoidProblem::kNotFinite;
    return result;
  }
  const Eigen::Vector3d eigenvalues = solver.eigenvalues();  // ascending
  if (eigenvalues.minCoeff() <= kMinVariance) {
    result.problem = EllipsoidProblem::kNotPositiveDefinite;
    return result;
  }
  if (eigenvalues.maxCoeff() >= kUnknownVariance) {
    result.problem = EllipsoidProblem::kUnknownVariance;
    return result;
  }
  Eigen::Matrix3d axes = solver.eigenvectors();
  // Eigenvectors come with arbitrary signs: flip one to make the axes a rotation (det +1), not a mirror.
  if (axes.determinant() < 0.0) axes.col(2) = -axes.col(2);
  result.ellipsoid.orientation = Eigen::Quaterniond(axes).normalized();
  result.ellipsoid.semi_axes_m = sigma_scale * eigenvalues.cwiseSqrt();
  return result;
}

Eigen::Matrix3d positionCovariance(const double* row_major_6x6) {
  constexpr int kPoseCovarianceDim = 6;
  Eigen::Matrix3d m;
  for (int r = 0; r < 3; ++r) {
    for (int c = 0; c < 3; ++c) m(r, c) = row_major_6x6[r * kPoseCovarianceDim + c];
  }
  return m;
}

}  // namespace docking_viz
