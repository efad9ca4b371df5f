#include "omni_base/kinematics.h"

#include <cmath>
#include <stdexcept>
#include <string>

namespace omni_base {

OmniKinematics::OmniKinematics(const WheelLayout& layout) : layout_(layout) {
  const std::size_t n = layout_.drive_angles_rad.size();
  if (n < 3) {
    throw std::invalid_argument("omni kinematics needs at least 3 wheels, got " + std::to_string(n));
  }
  if (!(layout_.center_distance_m > 0.0) || !std::isfinite(layout_.center_distance_m)) {
    throw std::invalid_argument("wheel centre distance L must be a positive number of metres");
  }
  if (!(layout_.wheel_radius_m > 0.0) || !std::isfinite(layout_.wheel_radius_m)) {
    throw std::invalid_argument("wheel radius r must be a positive number of metres");
  }
  inverse_matrix_.resize(static_cast<Eigen::Index>(n), 3);
  for (std::size_t i = 0; i < n; ++i) {
    const double a = layout_.drive_angles_rad[i];
    if (!std::isfinite(a)) throw std::invalid_argument("wheel drive angle is not finite");
    const auto row = static_cast<Eigen::Index>(i);
    inverse_matrix_(row, 0) = std::cos(a) / layout_.wheel_radius_m;
    inverse_matrix_(row, 1) = std::sin(a) / layout_.wheel_radius_m;
    inverse_matrix_(row, 2) = layout_.center_distance_m / layout_.wheel_radius_m;
  }
  // Wheels whose drive directions are (nearly) parallel cannot produce every planar motion.
  Eigen::JacobiSVD<Eigen::MatrixXd> svd(inverse_matrix_);
  const auto& sv = svd.singularValues();
  if (sv(2) < 1e-6 * sv(0)) {
    throw std::invalid_argument("wheel drive angles do not span the plane (rank-deficient layout)");
  }
  forward_matrix_ = (inverse_matrix_.transpose() * inverse_matrix_).inverse() * inverse_matrix_.transpose();
}

std::vector<double> OmniKinematics::inverse(const Twist2D& twist) const {
  const Eigen::Vector3d v(twist.vx, twist.vy, twist.wz);
  const Eigen::VectorXd w = inverse_matrix_ * v;
  return std::vector<double>(w.data(), w.data() + w.size());
}

Twist2D OmniKinematics::forward(const std::vector<double>& wheel_rad_s) const {
  if (wheel_rad_s.size() != wheelCount()) {
    throw std::invalid_argument("forward kinematics: expected " + std::to_string(wheelCount()) +
                                " wheel speeds, got " + std::to_string(wheel_rad_s.size()));
  }
  const Eigen::Map<const Eigen::VectorXd> w(wheel_rad_s.data(), static_cast<Eigen::Index>(wheel_rad_s.size()));
  const Eigen::Vector3d v = forward_matrix_ * w;
  return Twist2D{v(0), v(1), v(2)};
}

}  // namespace omni_base
