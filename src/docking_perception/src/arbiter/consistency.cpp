#include "docking_perception/arbiter/consistency.h"

#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <string>

#include <Eigen/Cholesky>
#include <boost/math/distributions/chi_squared.hpp>

namespace docking_perception {
namespace arbiter {
namespace {

// Floors of the relative motion allowed between two stamps: a still estimate may be wrong about being
// still (0.05 m/s over the 50 ms stamp tolerance: 2.5 mm; 0.05 rad/s: 0.14 deg).
constexpr double kMinRelativeSpeedMps = 0.05;
constexpr double kMinRelativeRateRadps = 0.05;

/// The chi-square value that `probability` of honest differences with `dof` degrees of freedom stay under.
double chiSquareGate(int dof, double probability) {
  return boost::math::quantile(boost::math::chi_squared(dof), probability);
}

/// Rotation taking `from` to `to`, as a rotation vector in the common frame (the covariances'
/// convention: a perturbation about the frame's axes, q_to = exp(d) q_from). Shortest way round.
Eigen::Vector3d rotationDifference(const Eigen::Quaterniond& from, const Eigen::Quaterniond& to) {
  Eigen::Quaterniond delta = to * from.conjugate();
  if (delta.w() < 0.0) delta.coeffs() *= -1.0;
  const Eigen::AngleAxisd axis_angle(delta.normalized());
  return axis_angle.angle() * axis_angle.axis();
}

}  // namespace

void validate(const ConsistencyConfig& c) { docking_settings::validateSettings(c); }

std::optional<ConsistencyTest> compare(const ComparablePose& a, const ComparablePose& b,
                                       const ConsistencyConfig& config) {
  ConsistencyTest test;
  test.dof = a.has_orientation && b.has_orientation ? 6 : 3;
  test.gate = chiSquareGate(test.dof, config.gate_probability);
  test.dt_s = std::abs(a.stamp_s - b.stamp_s);

  // How far the target may have moved between the two stamps: the faster of the two estimates'
  // own velocities, never less than the floors (a still estimate may be wrong about being still).
  const double speed = std::max({a.speed_mps, b.speed_mps, kMinRelativeSpeedMps});
  const double rate = std::max({a.rate_radps, b.rate_radps, kMinRelativeRateRadps});
  const double position_var = std::pow(speed * test.dt_s, 2) + std::pow(config.mount_sigma_m, 2);
  const double rotation_var = std::pow(rate * test.dt_s, 2) + std::pow(config.mount_sigma_rad, 2);

  const int n = test.dof;
  const Eigen::MatrixXd covariance = a.pose.covariance.topLeftCorner(n, n) + b.pose.covariance.topLeftCorner(n, n);
  if (!covariance.allFinite()) return std::nullopt;
  Eigen::MatrixXd s = covariance;
  s.topLeftCorner<3, 3>().diagonal().array() += position_var;
  if (n == 6) s.bottomRightCorner<3, 3>().diagonal().array() += rotation_var;

  Eigen::VectorXd difference(n);
  difference.head<3>() = b.pose.position - a.pose.position;
  if (n == 6) difference.tail<3>() = rotationDifference(a.pose.orientation, b.pose.orientation);
  if (!difference.allFinite()) return std::nullopt;

  // A source's covariance may be slightly indefinite (rounding): LDLT still solves it, and the added
  // floors keep it invertible; a negative result means a broken covariance, not agreement.
  const Eigen::LDLT<Eigen::MatrixXd> ldlt(s);
  if (ldlt.info() != Eigen::Success) return std::nullopt;
  test.chi2 = difference.dot(ldlt.solve(difference));
  if (!std::isfinite(test.chi2) || test.chi2 < 0.0) return std::nullopt;
  test.agree = test.chi2 <= test.gate;
  return test;
}

}  // namespace arbiter
}  // namespace docking_perception
