// Planar odometry: integrates body twists into a pose (ROS-free).
#pragma once

#include "omni_base/kinematics.h"

namespace omni_base {

/// Integrates the body twist over each interval exactly along the circular arc it describes (a
/// constant twist moves the base on an arc, not on a straight chord), so a long turn does not drift.
class OdometryIntegrator {
 public:
  void reset(const Pose2D& pose = Pose2D{}) { pose_ = pose; }
  /// Advances the pose by a constant body twist held for dt_s seconds.
  const Pose2D& integrate(const Twist2D& twist, double dt_s);
  /// Advances the pose by a body-frame displacement (dx, dy, dyaw) travelled on one arc.
  const Pose2D& integrateDisplacement(const Twist2D& displacement);
  const Pose2D& pose() const { return pose_; }

 private:
  Pose2D pose_;
};

/// Wraps an angle into (-pi, pi].
double normalizeAngle(double angle_rad);

}  // namespace omni_base
