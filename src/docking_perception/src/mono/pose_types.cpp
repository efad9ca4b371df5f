#include "docking_perception/mono/pose_types.h"

#include <Eigen/LU>
#include <cmath>
#include <ctime>

namespace docking_perception {
namespace mono {

bool CameraIntrinsics::isValid(std::string* reason) const {
  std::string why;
  if (!(fx > 0.0) || !(fy > 0.0)) {
    why = "focal lengths must be positive (fx=" + std::to_string(fx) + ", fy=" + std::to_string(fy) + ")";
  } else if (width <= 0 || height <= 0) {
    why = "image size must be positive (" + std::to_string(width) + "x" + std::to_string(height) + ")";
  } else if (!std::isfinite(cx) || !std::isfinite(cy)) {
    why = "principal point is not finite";
  }
  if (reason != nullptr) *reason = why;
  return why.empty();
}

Eigen::Vector2d CameraIntrinsics::project(const Eigen::Vector3d& p) const {
  return {fx * p.x() / p.z() + cx, fy * p.y() / p.z() + cy};
}

Eigen::Vector3d CameraIntrinsics::ray(const Eigen::Vector2d& pixel) const {
  return {(pixel.x() - cx) / fx, (pixel.y() - cy) / fy, 1.0};
}

Eigen::Matrix3d skew(const Eigen::Vector3d& v) {
  Eigen::Matrix3d m;
  m << 0.0, -v.z(), v.y(), v.z(), 0.0, -v.x(), -v.y(), v.x(), 0.0;
  return m;
}

Eigen::Matrix3d rotationExp(const Eigen::Vector3d& rotation_vector) {
  const double angle = rotation_vector.norm();
  if (angle < 1e-12) return Eigen::Matrix3d::Identity() + skew(rotation_vector);
  return Eigen::AngleAxisd(angle, rotation_vector / angle).toRotationMatrix();
}

Eigen::Vector3d rotationLog(const Eigen::Matrix3d& rotation) {
  const Eigen::AngleAxisd aa(rotation);
  return aa.angle() * aa.axis();
}

double rotationAngleBetween(const Eigen::Matrix3d& a, const Eigen::Matrix3d& b) {
  return Eigen::AngleAxisd(a * b.transpose()).angle();
}

double reprojectionRms(const CameraIntrinsics& camera, const Eigen::Matrix3d& rotation,
                       const Eigen::Vector3d& translation, const std::vector<Eigen::Vector3d>& model_points,
                       const std::vector<Eigen::Vector2d>& image_points) {
  if (model_points.empty() || model_points.size() != image_points.size()) return 0.0;
  double sum = 0.0;
  for (size_t i = 0; i < model_points.size(); ++i) {
    sum += (camera.project(rotation * model_points[i] + translation) - image_points[i]).squaredNorm();
  }
  return std::sqrt(sum / static_cast<double>(model_points.size()));
}

Eigen::MatrixXd reprojectionJacobian(const CameraIntrinsics& camera, const Eigen::Matrix3d& rotation,
                                     const Eigen::Vector3d& translation,
                                     const std::vector<Eigen::Vector3d>& model_points) {
  Eigen::MatrixXd jacobian(2 * model_points.size(), 6);
  for (size_t i = 0; i < model_points.size(); ++i) {
    const Eigen::Vector3d rotated = rotation * model_points[i];
    const Eigen::Vector3d p = rotated + translation;
    const double inv_z = 1.0 / p.z();
    Eigen::Matrix<double, 2, 3> d_pixel_d_point;
    d_pixel_d_point << camera.fx * inv_z, 0.0, -camera.fx * p.x() * inv_z * inv_z,  //
        0.0, camera.fy * inv_z, -camera.fy * p.y() * inv_z * inv_z;
    // d(point)/d(dt) = I; d(point)/d(dtheta) = -[R m]x, since Exp(dtheta) R m ~ R m + dtheta x R m.
    jacobian.block<2, 3>(2 * i, 0) = d_pixel_d_point;
    jacobian.block<2, 3>(2 * i, 3) = -d_pixel_d_point * skew(rotated);
  }
  return jacobian;
}

bool leastSquaresPoseCovariance(const CameraIntrinsics& camera, const Eigen::Matrix3d& rotation,
                                const Eigen::Vector3d& translation,
                                const std::vector<Eigen::Vector3d>& model_points, double pixel_variance,
                                Matrix6d* covariance) {
  *covariance = Matrix6d::Identity() * 1e6;
  if (model_points.size() < 3) return false;
  const Eigen::MatrixXd jacobian = reprojectionJacobian(camera, rotation, translation, model_points);
  const Matrix6d information = jacobian.transpose() * jacobian;
  Eigen::FullPivLU<Matrix6d> lu(information);
  if (!lu.isInvertible()) return false;
  *covariance = pixel_variance * lu.inverse();
  *covariance = 0.5 * (*covariance + covariance->transpose());
  return true;
}

double threadCpuTimeMs() {
  timespec ts{};
  clock_gettime(CLOCK_THREAD_CPUTIME_ID, &ts);
  return static_cast<double>(ts.tv_sec) * 1e3 + static_cast<double>(ts.tv_nsec) * 1e-6;
}

}  // namespace mono
}  // namespace docking_perception
