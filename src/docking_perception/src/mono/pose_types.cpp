#include "docking_perception/mono/pose_types.h"

#include <Eigen/Cholesky>
#include <Eigen/Geometry>
#include <Eigen/LU>
#include <limits>
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

namespace {

// One point's 2 x 6 block of reprojectionJacobian: `rotated` is R m, the point before the translation.
Eigen::Matrix<double, 2, 6> pointJacobian(const CameraIntrinsics& camera, const Eigen::Vector3d& rotated,
                                          const Eigen::Vector3d& translation) {
  const Eigen::Vector3d p = rotated + translation;
  const double inv_z = 1.0 / p.z();
  Eigen::Matrix<double, 2, 3> d_pixel_d_point;
  d_pixel_d_point << camera.fx * inv_z, 0.0, -camera.fx * p.x() * inv_z * inv_z,  //
      0.0, camera.fy * inv_z, -camera.fy * p.y() * inv_z * inv_z;
  // d(point)/d(dt) = I; d(point)/d(dtheta) = -[R m]x, since Exp(dtheta) R m ~ R m + dtheta x R m.
  Eigen::Matrix<double, 2, 6> block;
  block.leftCols<3>() = d_pixel_d_point;
  block.rightCols<3>() = -d_pixel_d_point * skew(rotated);
  return block;
}

// Sum of squared reprojection errors; infinite when a point is not in front of the camera.
double reprojectionCost(const CameraIntrinsics& camera, const Eigen::Matrix3d& rotation,
                        const Eigen::Vector3d& translation, const std::vector<Eigen::Vector3d>& model_points,
                        const std::vector<Eigen::Vector2d>& image_points) {
  double sum = 0.0;
  for (size_t i = 0; i < model_points.size(); ++i) {
    const Eigen::Vector3d p = rotation * model_points[i] + translation;
    if (!(p.z() > 0.0)) return std::numeric_limits<double>::infinity();
    sum += (camera.project(p) - image_points[i]).squaredNorm();
  }
  return sum;
}

}  // namespace

Eigen::MatrixXd reprojectionJacobian(const CameraIntrinsics& camera, const Eigen::Matrix3d& rotation,
                                     const Eigen::Vector3d& translation,
                                     const std::vector<Eigen::Vector3d>& model_points) {
  Eigen::MatrixXd jacobian(2 * model_points.size(), 6);
  for (size_t i = 0; i < model_points.size(); ++i) {
    jacobian.block<2, 6>(2 * i, 0) = pointJacobian(camera, rotation * model_points[i], translation);
  }
  return jacobian;
}

int refinePoseLevenbergMarquardt(const CameraIntrinsics& camera, const std::vector<Eigen::Vector3d>& model_points,
                                 const std::vector<Eigen::Vector2d>& image_points, int max_iterations,
                                 Eigen::Matrix3d* rotation, Eigen::Vector3d* translation) {
  if (model_points.size() < 3 || model_points.size() != image_points.size()) return 0;
  constexpr double kInitialDamping = 1e-3;  // relative to the normal matrix's diagonal
  constexpr double kMinDamping = 1e-12;     // after many good steps: Gauss-Newton, but never exactly
  constexpr double kMaxDamping = 1e10;      // past this no step lowers the cost: a minimum
  constexpr double kMinStep = 1e-12;        // m and rad: converged
  double cost = reprojectionCost(camera, *rotation, *translation, model_points, image_points);
  if (!std::isfinite(cost)) return 0;
  double damping = kInitialDamping;
  for (int iteration = 1; iteration <= max_iterations; ++iteration) {
    // Normal equations of the linearised residuals (observed - projected) at the current pose.
    Matrix6d normal = Matrix6d::Zero();
    Vector6d gradient = Vector6d::Zero();
    for (size_t i = 0; i < model_points.size(); ++i) {
      const Eigen::Vector3d rotated = *rotation * model_points[i];
      const Eigen::Matrix<double, 2, 6> block = pointJacobian(camera, rotated, *translation);
      normal.noalias() += block.transpose() * block;
      gradient.noalias() += block.transpose() * (image_points[i] - camera.project(rotated + *translation));
    }
    bool lowered = false;
    Vector6d step = Vector6d::Zero();
    while (!lowered && damping <= kMaxDamping) {
      Matrix6d damped = normal;
      damped.diagonal() *= 1.0 + damping;
      step = damped.ldlt().solve(gradient);
      const Eigen::Vector3d candidate_translation = *translation + step.head<3>();
      const Eigen::Matrix3d candidate_rotation = rotationExp(step.tail<3>()) * *rotation;
      const double candidate_cost =
          reprojectionCost(camera, candidate_rotation, candidate_translation, model_points, image_points);
      if (candidate_cost <= cost) {
        lowered = true;
        cost = candidate_cost;
        *translation = candidate_translation;
        *rotation = candidate_rotation;
        damping = std::max(damping * 0.1, kMinDamping);
      } else {
        damping *= 10.0;
      }
    }
    if (!lowered || step.norm() < kMinStep) return iteration;
  }
  return max_iterations;
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
