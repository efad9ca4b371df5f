#include "omni_base/odometry.h"

#include <cmath>

namespace omni_base {

double normalizeAngle(double angle_rad) {
  double a = std::fmod(angle_rad + M_PI, 2.0 * M_PI);
  if (a <= 0.0) a += 2.0 * M_PI;
  return a - M_PI;
}

const Pose2D& OdometryIntegrator::integrate(const Twist2D& twist, double dt_s) {
  if (!(dt_s > 0.0)) return pose_;
  return integrateDisplacement(Twist2D{twist.vx * dt_s, twist.vy * dt_s, twist.wz * dt_s});
}

const Pose2D& OdometryIntegrator::integrateDisplacement(const Twist2D& d) {
  if (!std::isfinite(d.vx) || !std::isfinite(d.vy) || !std::isfinite(d.wz)) return pose_;
  const double dth = d.wz;
  // Body-frame chord of the arc: for small turns use the series limit to avoid 0/0.
  double sin_term;  // sin(dth)/dth
  double cos_term;  // (1 - cos(dth))/dth
  if (std::abs(dth) < 1e-9) {
    sin_term = 1.0 - dth * dth / 6.0;
    cos_term = dth / 2.0;
  } else {
    sin_term = std::sin(dth) / dth;
    cos_term = (1.0 - std::cos(dth)) / dth;
  }
  const double chord_x = sin_term * d.vx - cos_term * d.vy;
  const double chord_y = cos_term * d.vx + sin_term * d.vy;
  const double c = std::cos(pose_.yaw);
  const double s = std::sin(pose_.yaw);
  pose_.x += c * chord_x - s * chord_y;
  pose_.y += s * chord_x + c * chord_y;
  pose_.yaw = normalizeAngle(pose_.yaw + dth);
  return pose_;
}

}  // namespace omni_base
