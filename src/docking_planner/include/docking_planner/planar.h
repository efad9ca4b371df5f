// Planar (odom-frame) geometry shared by the planner core. ROS-free.
#pragma once

#include <Eigen/Core>
#include <cmath>

namespace docking_planner {

using Vec2 = Eigen::Vector2d;

/// A planar pose: position in m, yaw in rad (counter-clockwise from x).
struct Pose2D {
  double x{0.0};
  double y{0.0};
  double yaw{0.0};
  Vec2 position() const { return Vec2(x, y); }
};

/// A body-frame velocity command for base_link: m/s, m/s, rad/s.
struct BodyTwist {
  double vx{0.0};
  double vy{0.0};
  double wz{0.0};
};

/// Wraps an angle into [-pi, pi).
inline double wrapAngle(double a) {
  a = std::fmod(a + M_PI, 2.0 * M_PI);
  if (a < 0.0) a += 2.0 * M_PI;
  return a - M_PI;
}

/// The unit vector at angle a.
inline Vec2 unitAt(double a) { return Vec2(std::cos(a), std::sin(a)); }

/// z x v: the vector v turned by +90 degrees (for omega x r in the plane).
inline Vec2 perpendicular(const Vec2& v) { return Vec2(-v.y(), v.x()); }

/// Scales v down so that its norm is at most `limit` (direction kept).
inline Vec2 clampNorm(const Vec2& v, double limit) {
  const double n = v.norm();
  return n > limit && n > 0.0 ? Vec2(v * (limit / n)) : v;
}

inline double clampAbs(double v, double limit) { return v > limit ? limit : (v < -limit ? -limit : v); }

}  // namespace docking_planner
