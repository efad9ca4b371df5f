// The uncertainty ellipsoid of a 3x3 position covariance, for display. ROS-free.
// Its axes are the covariance's eigenvectors, its semi-axes sigma_scale standard deviations along them.
// A covariance that is not a usable one (NaN, asymmetric, not positive definite, or carrying the
// "component not valid" variance of TargetEstimate) gives a problem code instead of a shape.
#pragma once

#include <Eigen/Core>
#include <Eigen/Geometry>

namespace docking_viz {

/// Standard deviations drawn along each axis by default: 3 sigma holds ~97% of a 3D Gaussian.
constexpr double kDefaultSigmaScale = 3.0;
/// TargetEstimate marks a component that is not valid with a variance of 1e6 or more: not a shape to draw.
constexpr double kUnknownVariance = 1e6;
/// A variance at or below this (m^2: 1 micrometre sigma) is degenerate: a flat ellipsoid says "exact",
/// which no estimate is; refused like a negative one.
constexpr double kMinVariance = 1e-12;
/// Relative tolerance of the symmetry check (a frame change leaves ~1e-16 relative rounding).
constexpr double kSymmetryTolerance = 1e-6;

enum class EllipsoidProblem {
  kNone = 0,
  kNotFinite,            ///< NaN or infinite entry
  kNotSymmetric,         ///< not a covariance matrix
  kNotPositiveDefinite,  ///< an eigenvalue at or below kMinVariance
  kUnknownVariance,      ///< an eigenvalue at or above kUnknownVariance: the position is not valid
};
const char* ellipsoidProblemName(EllipsoidProblem problem);

struct Ellipsoid {
  /// Rotation from the ellipsoid's axes to the covariance's frame: column i of its matrix is axis i.
  Eigen::Quaterniond orientation{Eigen::Quaterniond::Identity()};
  /// Half-lengths along the axes, m (sigma_scale * sqrt(eigenvalue)), ascending.
  Eigen::Vector3d semi_axes_m{Eigen::Vector3d::Zero()};
};

struct EllipsoidResult {
  EllipsoidProblem problem{EllipsoidProblem::kNone};
  Ellipsoid ellipsoid;  ///< meaningful only when problem == kNone
  bool valid() const { return problem == EllipsoidProblem::kNone; }
};

/// The ellipsoid of `covariance` (m^2). sigma_scale must be positive and finite (else kNotFinite).
EllipsoidResult covarianceEllipsoid(const Eigen::Matrix3d& covariance, double sigma_scale = kDefaultSigmaScale);

/// The top-left 3x3 (position) block of a row-major 6x6 pose covariance (TargetEstimate's layout).
Eigen::Matrix3d positionCovariance(const double* row_major_6x6);

}  // namespace docking_viz
