#include "docking_perception/arbiter/frame_change.h"

namespace docking_perception {
namespace arbiter {
namespace {

Matrix6d blockRotation(const Eigen::Matrix3d& r) {
  Matrix6d big = Matrix6d::Zero();
  big.topLeftCorner<3, 3>() = r;
  big.bottomRightCorner<3, 3>() = r;
  return big;
}

}  // namespace

PoseWithCovariance3 changeFrame(const Eigen::Isometry3d& out_from_in, const PoseWithCovariance3& pose) {
  const Eigen::Matrix3d r = out_from_in.rotation();
  PoseWithCovariance3 out;
  out.position = out_from_in * pose.position;
  out.orientation = Eigen::Quaterniond(r) * pose.orientation;
  out.orientation.normalize();
  const Matrix6d j = blockRotation(r);
  out.covariance = j * pose.covariance * j.transpose();
  return out;
}

TwistWithCovariance3 changeFrameRigidMount(const Eigen::Matrix3d& out_from_in_rotation,
                                           const TwistWithCovariance3& twist) {
  TwistWithCovariance3 out;
  out.linear = out_from_in_rotation * twist.linear;
  out.angular = out_from_in_rotation * twist.angular;
  const Matrix6d j = blockRotation(out_from_in_rotation);
  out.covariance = j * twist.covariance * j.transpose();
  return out;
}

}  // namespace arbiter
}  // namespace docking_perception
