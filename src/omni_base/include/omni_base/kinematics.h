// Kinematics of an omni-wheel base with N >= 3 wheels (ROS-free).
//
// Wheel i drives along direction a_i (angle from base x, counter-clockwise) at distance L from the
// centre, with radius r. Its angular velocity for a body twist (vx, vy, wz) is
//   qdot_i = (cos(a_i) vx + sin(a_i) vy + L wz) / r        (the paper's qdot = B^T Xdot / r, eq. 10)
// The forward map is the least-squares inverse of that, exact for N = 3.
#pragma once

#include <Eigen/Dense>
#include <vector>

namespace omni_base {

/// Planar body velocity in base_link: m/s, m/s, rad/s.
struct Twist2D {
  double vx{0.0};
  double vy{0.0};
  double wz{0.0};
};

/// Planar pose of base_link in odom: m, m, rad.
struct Pose2D {
  double x{0.0};
  double y{0.0};
  double yaw{0.0};
};

struct WheelLayout {
  std::vector<double> drive_angles_rad;  ///< drive direction of each wheel, from base x, CCW
  double center_distance_m{0.0};         ///< L: distance from the base centre to each wheel
  double wheel_radius_m{0.0};            ///< r
};

class OmniKinematics {
 public:
  /// Throws std::invalid_argument when the layout cannot produce every planar motion.
  explicit OmniKinematics(const WheelLayout& layout);

  std::size_t wheelCount() const { return layout_.drive_angles_rad.size(); }
  const WheelLayout& layout() const { return layout_; }

  /// Wheel angular velocities (rad/s) for a body twist.
  std::vector<double> inverse(const Twist2D& twist) const;
  /// Body twist from wheel angular velocities (rad/s); least squares for N > 3.
  Twist2D forward(const std::vector<double>& wheel_rad_s) const;

 private:
  WheelLayout layout_;
  Eigen::MatrixXd inverse_matrix_;  // N x 3: wheel speeds = inverse_matrix_ * [vx vy wz]
  Eigen::MatrixXd forward_matrix_;  // 3 x N: pseudo-inverse of inverse_matrix_
};

}  // namespace omni_base
