// Small shared types of the monocular pose core: camera intrinsics, a pose with its covariance, and
// the rotation / projection helpers every solver needs. ROS-free.
#pragma once

#include <Eigen/Core>
#include <Eigen/Geometry>
#include <string>
#include <vector>

namespace docking_perception {
namespace mono {

using Matrix6d = Eigen::Matrix<double, 6, 6>;
using Vector6d = Eigen::Matrix<double, 6, 1>;

// Pinhole intrinsics of a rectified image (no distortion: mono_pose works on image_rect, whose
// camera_info P matrix gives these numbers).
struct CameraIntrinsics {
  double fx = 0.0;
  double fy = 0.0;
  double cx = 0.0;
  double cy = 0.0;
  int width = 0;
  int height = 0;

  // False (with the reason) when focal lengths or the image size are not positive.
  bool isValid(std::string* reason = nullptr) const;
  Eigen::Vector2d project(const Eigen::Vector3d& point_camera) const;
  // The viewing ray through a pixel, with z = 1.
  Eigen::Vector3d ray(const Eigen::Vector2d& pixel) const;
};

// Pose of the target frame in the camera's optical frame: x_camera = rotation * x_target + translation.
// Covariance: 6x6 over (translation x, y, z [m], rotation about the camera's x, y, z [rad]), where a
// rotation perturbation dtheta means R' = Exp(dtheta) * R (the convention of TargetEstimate).
struct PoseWithCovariance {
  Eigen::Matrix3d rotation = Eigen::Matrix3d::Identity();
  Eigen::Vector3d translation = Eigen::Vector3d::Zero();
  Matrix6d covariance = Matrix6d::Identity();
};

// Linear and angular velocity of the target relative to the camera, in the camera frame.
// Covariance over (vx, vy, vz, wx, wy, wz).
struct TwistWithCovariance {
  bool valid = false;
  Eigen::Vector3d linear = Eigen::Vector3d::Zero();
  Eigen::Vector3d angular = Eigen::Vector3d::Zero();
  Matrix6d covariance = Matrix6d::Identity() * 1e6;
};

// SO(3) exponential and logarithm (rotation vector <-> rotation matrix).
Eigen::Matrix3d rotationExp(const Eigen::Vector3d& rotation_vector);
Eigen::Vector3d rotationLog(const Eigen::Matrix3d& rotation);
// Angle of the rotation between two orientations, rad, in [0, pi].
double rotationAngleBetween(const Eigen::Matrix3d& a, const Eigen::Matrix3d& b);
Eigen::Matrix3d skew(const Eigen::Vector3d& v);

// RMS reprojection error, px, of model points under a pose.
double reprojectionRms(const CameraIntrinsics& camera, const Eigen::Matrix3d& rotation,
                       const Eigen::Vector3d& translation, const std::vector<Eigen::Vector3d>& model_points,
                       const std::vector<Eigen::Vector2d>& image_points);

// 2N x 6 Jacobian of the projected model points with respect to (dt, dtheta) as defined above.
Eigen::MatrixXd reprojectionJacobian(const CameraIntrinsics& camera, const Eigen::Matrix3d& rotation,
                                     const Eigen::Vector3d& translation,
                                     const std::vector<Eigen::Vector3d>& model_points);

// Levenberg-Marquardt on the reprojection error (pinhole, no distortion: the images are rectified) from
// (rotation, translation), updated in place to the minimum near them; the steps as in
// reprojectionJacobian (R <- Exp(dtheta) R). Stops when a step is below 1e-12 or none lowers the cost.
// Returns the iterations run (0: fewer than 3 points, or a start with a point behind the camera).
int refinePoseLevenbergMarquardt(const CameraIntrinsics& camera, const std::vector<Eigen::Vector3d>& model_points,
                                 const std::vector<Eigen::Vector2d>& image_points, int max_iterations,
                                 Eigen::Matrix3d* rotation, Eigen::Vector3d* translation);

// Gauss-Newton covariance of a least-squares pose: pixel_variance * (J^T J)^-1. Returns false when J^T J
// is singular (fewer than 3 non-collinear points); the covariance is then set to 1e6 * I.
bool leastSquaresPoseCovariance(const CameraIntrinsics& camera, const Eigen::Matrix3d& rotation,
                                const Eigen::Vector3d& translation,
                                const std::vector<Eigen::Vector3d>& model_points, double pixel_variance,
                                Matrix6d* covariance);

// Per-thread CPU time in ms (the processing_time_ms of TargetEstimate is CPU time, not wall time).
double threadCpuTimeMs();

}  // namespace mono
}  // namespace docking_perception
