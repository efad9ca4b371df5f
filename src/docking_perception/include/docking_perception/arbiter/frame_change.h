// Re-expressing a target estimate (pose, twist, covariances) in another camera's frame (ROS-free).
#pragma once

#include <Eigen/Geometry>

namespace docking_perception {
namespace arbiter {

using Matrix6d = Eigen::Matrix<double, 6, 6>;

/// Pose of the target in some frame, covariance over (x, y, z, rotation about x, y, z) in that frame.
struct PoseWithCovariance3 {
  Eigen::Vector3d position{Eigen::Vector3d::Zero()};
  Eigen::Quaterniond orientation{Eigen::Quaterniond::Identity()};
  Matrix6d covariance{Matrix6d::Zero()};
};

/// Velocity of the target origin relative to a camera, expressed in that camera's frame.
struct TwistWithCovariance3 {
  Eigen::Vector3d linear{Eigen::Vector3d::Zero()};
  Eigen::Vector3d angular{Eigen::Vector3d::Zero()};
  Matrix6d covariance{Matrix6d::Zero()};
};

/// Pose in frame `in` -> pose in frame `out`, given the pose of `in` in `out`. The covariance is
/// rotated block-wise (the translation of a fixed transform adds no uncertainty; the mount's own
/// calibration error is not added).
PoseWithCovariance3 changeFrame(const Eigen::Isometry3d& out_from_in, const PoseWithCovariance3& pose);

/// Twist relative to camera `in` -> twist relative to camera `out`, for cameras rigidly mounted on the
/// same body. Because neither camera moves relative to the other, the target origin's velocity and
/// the angular velocity relative to `out` are those relative to `in`, rotated: v' = R v, w' = R w.
/// (This holds for the velocity of the target origin, which is what TargetEstimate carries; it would
/// not hold for a screw twist referred to the camera origin, nor for a mount that flexes.)
TwistWithCovariance3 changeFrameRigidMount(const Eigen::Matrix3d& out_from_in_rotation,
                                           const TwistWithCovariance3& twist);

}  // namespace arbiter
}  // namespace docking_perception
