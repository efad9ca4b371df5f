#include "docking_perception/mono/collinear_five_point_solver.h"

#include <Eigen/Geometry>
#include <Eigen/SVD>
#include <vector>

namespace docking_perception {
namespace mono {
namespace {

// Orthonormal frame (columns) from a first direction and a second, non-parallel one.
bool gramSchmidtFrame(const Eigen::Vector3d& first, const Eigen::Vector3d& second, Eigen::Matrix3d* frame) {
  const double first_norm = first.norm();
  if (first_norm < 1e-12) return false;
  const Eigen::Vector3d e1 = first / first_norm;
  const Eigen::Vector3d orthogonal = second - second.dot(e1) * e1;
  if (orthogonal.norm() < 1e-9 * std::max(1.0, second.norm())) return false;
  const Eigen::Vector3d e2 = orthogonal.normalized();
  frame->col(0) = e1;
  frame->col(1) = e2;
  frame->col(2) = e1.cross(e2);
  return true;
}

// Depths of a collinear triple whose middle point is the midpoint of the ends; returns the three 3D points.
bool solveTriple(const Eigen::Vector3d& d1, const Eigen::Vector3d& d2, const Eigen::Vector3d& d3, double length,
                 std::array<Eigen::Vector3d, 3>* points) {
  Eigen::Matrix3d system;
  system.col(0) = -0.5 * d1;
  system.col(1) = d2;
  system.col(2) = -0.5 * d3;
  const Eigen::JacobiSVD<Eigen::Matrix3d> svd(system, Eigen::ComputeFullV);
  Eigen::Vector3d depths = svd.matrixV().col(2);
  if (depths.sum() < 0.0) depths = -depths;
  if (depths.minCoeff() <= 0.0) return false;  // a point behind the camera: not a real triple
  const double span = (depths(0) * d1 - depths(2) * d3).norm();
  if (span < 1e-12) return false;
  depths *= length / span;
  (*points)[0] = depths(0) * d1;
  (*points)[1] = depths(1) * d2;
  (*points)[2] = depths(2) * d3;
  return true;
}

}  // namespace

CollinearFivePointSolver::CollinearFivePointSolver(const MarkerPoints& markers) : markers_(markers) {
  length_a_m_ = (markers_[0] - markers_[2]).norm();
  length_b_m_ = (markers_[4] - markers_[2]).norm();
  model_frame_.setIdentity();
  gramSchmidtFrame(markers_[0] - markers_[2], markers_[4] - markers_[2], &model_frame_);
}

bool CollinearFivePointSolver::solve(const CameraIntrinsics& camera, const MarkerPixels& pixels,
                                     FivePointSolution* solution, std::string* reason) const {
  std::array<Eigen::Vector3d, kMarkerCount> rays;
  for (int i = 0; i < kMarkerCount; ++i) rays[static_cast<size_t>(i)] = camera.ray(pixels[static_cast<size_t>(i)]);

  std::array<Eigen::Vector3d, 3> triple_a;  // markers 0, 1, 2
  std::array<Eigen::Vector3d, 3> triple_b;  // markers 2, 3, 4
  if (!solveTriple(rays[0], rays[1], rays[2], length_a_m_, &triple_a)) {
    if (reason) *reason = "triple A (markers 0-1-2) has no solution in front of the camera";
    return false;
  }
  if (!solveTriple(rays[2], rays[3], rays[4], length_b_m_, &triple_b)) {
    if (reason) *reason = "triple B (markers 2-3-4) has no solution in front of the camera";
    return false;
  }
  Eigen::Matrix3d camera_frame;
  if (!gramSchmidtFrame(triple_a[0] - triple_a[2], triple_b[2] - triple_b[0], &camera_frame)) {
    if (reason) *reason = "the two marker arms are parallel in 3D";
    return false;
  }
  solution->rotation = camera_frame * model_frame_.transpose();
  solution->points_camera = {triple_a[0], triple_a[1], 0.5 * (triple_a[2] + triple_b[0]), triple_b[1], triple_b[2]};
  solution->shared_marker_gap_m = (triple_a[2] - triple_b[0]).norm();

  Eigen::Vector3d mean_camera = Eigen::Vector3d::Zero();
  Eigen::Vector3d mean_model = Eigen::Vector3d::Zero();
  for (int i = 0; i < kMarkerCount; ++i) {
    mean_camera += solution->points_camera[static_cast<size_t>(i)];
    mean_model += markers_[static_cast<size_t>(i)];
  }
  solution->translation = (mean_camera - solution->rotation * mean_model) / kMarkerCount;

  const std::vector<Eigen::Vector3d> model(markers_.begin(), markers_.end());
  const std::vector<Eigen::Vector2d> image(pixels.begin(), pixels.end());
  solution->reprojection_rms_px = reprojectionRms(camera, solution->rotation, solution->translation, model, image);
  return true;
}

bool CollinearFivePointSolver::solveWithCovariance(const CameraIntrinsics& camera, const MarkerPixels& pixels,
                                                   double pixel_variance, FivePointSolution* solution,
                                                   Matrix6d* covariance, std::string* reason) const {
  if (!solve(camera, pixels, solution, reason)) return false;
  // Central differences: the closed form is smooth near a valid solution; 0.05 px keeps the truncation
  // error far below the noise level while staying well above rounding.
  constexpr double kStepPx = 0.05;
  Eigen::Matrix<double, 6, 2 * kMarkerCount> jacobian;
  for (int k = 0; k < 2 * kMarkerCount; ++k) {
    MarkerPixels plus = pixels;
    MarkerPixels minus = pixels;
    plus[static_cast<size_t>(k / 2)](k % 2) += kStepPx;
    minus[static_cast<size_t>(k / 2)](k % 2) -= kStepPx;
    FivePointSolution solution_plus;
    FivePointSolution solution_minus;
    if (!solve(camera, plus, &solution_plus, nullptr) || !solve(camera, minus, &solution_minus, nullptr)) {
      if (reason) *reason = "the 5-point solution is at a degenerate configuration (no Jacobian)";
      *covariance = Matrix6d::Identity() * 1e6;
      return true;  // the pose itself is valid; its covariance says it is not to be trusted
    }
    jacobian.block<3, 1>(0, k) = (solution_plus.translation - solution_minus.translation) / (2.0 * kStepPx);
    jacobian.block<3, 1>(3, k) =
        rotationLog(solution_plus.rotation * solution_minus.rotation.transpose()) / (2.0 * kStepPx);
  }
  *covariance = pixel_variance * jacobian * jacobian.transpose();
  return true;
}

}  // namespace mono
}  // namespace docking_perception
