#include "docking_perception/mono/planar_pnp_solver.h"

#include <algorithm>
#include <cmath>
#include <opencv2/calib3d.hpp>
#include <opencv2/core/eigen.hpp>

namespace docking_perception {
namespace mono {
namespace {

constexpr int kMaxRefinementIterations = 20;

Eigen::Matrix3d toRotation(const cv::Mat& rvec) {
  cv::Mat rotation_cv;
  cv::Rodrigues(rvec, rotation_cv);
  Eigen::Matrix3d rotation;
  cv::cv2eigen(rotation_cv, rotation);
  return rotation;
}

Eigen::Vector3d toVector(const cv::Mat& vec) {
  cv::Mat as_double;
  vec.convertTo(as_double, CV_64F);
  return {as_double.at<double>(0), as_double.at<double>(1), as_double.at<double>(2)};
}

// One of IPPE's solutions.
struct Candidate {
  Eigen::Matrix3d rotation;
  Eigen::Vector3d translation;
  double rms;
};

// IPPE's solutions in front of the camera, lowest reprojection error first; empty (with the reason) when none.
std::vector<Candidate> ippeSolutions(const CameraIntrinsics& camera, const std::vector<Eigen::Vector3d>& model_points,
                                     const std::vector<Eigen::Vector2d>& image_points, std::string* reason) {
  std::vector<cv::Point3d> object;
  std::vector<cv::Point2d> image;
  object.reserve(model_points.size());
  image.reserve(image_points.size());
  for (size_t i = 0; i < model_points.size(); ++i) {
    object.emplace_back(model_points[i].x(), model_points[i].y(), model_points[i].z());
    image.emplace_back(image_points[i].x(), image_points[i].y());
  }
  const cv::Matx33d camera_matrix(camera.fx, 0.0, camera.cx, 0.0, camera.fy, camera.cy, 0.0, 0.0, 1.0);
  std::vector<cv::Mat> rvecs;
  std::vector<cv::Mat> tvecs;
  cv::Mat errors;
  int count = 0;
  try {
    count = cv::solvePnPGeneric(object, image, camera_matrix, cv::noArray(), rvecs, tvecs, false,
                                cv::SOLVEPNP_IPPE, cv::noArray(), cv::noArray(), errors);
  } catch (const cv::Exception& e) {
    if (reason) *reason = std::string("IPPE failed: ") + e.what();
    return {};
  }
  if (count < 1) {
    if (reason) *reason = "IPPE found no solution (points not coplanar or degenerate)";
    return {};
  }
  errors.convertTo(errors, CV_64F);
  std::vector<Candidate> candidates;
  for (int i = 0; i < count; ++i) {
    const Eigen::Matrix3d rotation = toRotation(rvecs[static_cast<size_t>(i)]);
    const Eigen::Vector3d translation = toVector(tvecs[static_cast<size_t>(i)]);
    if (translation.z() <= 0.0) continue;  // behind the camera
    candidates.push_back({rotation, translation, errors.at<double>(i)});
  }
  if (candidates.empty() && reason) *reason = "IPPE solutions are all behind the camera";
  std::sort(candidates.begin(), candidates.end(),
            [](const Candidate& a, const Candidate& b) { return a.rms < b.rms; });
  return candidates;
}

}  // namespace

bool PlanarPnpSolver::solve(const CameraIntrinsics& camera, const std::vector<Eigen::Vector3d>& model_points,
                            const std::vector<Eigen::Vector2d>& image_points,
                            const Eigen::Matrix3d* previous_rotation, PlanarPnpSolution* solution,
                            std::string* reason) const {
  if (model_points.size() != image_points.size()) {
    if (reason) *reason = "model and image point counts differ";
    return false;
  }
  if (model_points.size() < 4) {
    if (reason) *reason = "PnP needs at least 4 points, got " + std::to_string(model_points.size());
    return false;
  }
  const std::vector<Candidate> candidates = ippeSolutions(camera, model_points, image_points, reason);
  if (candidates.empty()) return false;
  size_t chosen = 0;
  *solution = PlanarPnpSolution();
  if (candidates.size() == 2) {
    const double best = candidates[0].rms;
    const double other = candidates[1].rms;
    solution->ambiguous = other <= params_.ambiguity_ratio * best ||
                          (best <= params_.ambiguity_floor_px && other <= params_.ambiguity_floor_px);
    if (solution->ambiguous && previous_rotation != nullptr) {
      const double angle0 = rotationAngleBetween(candidates[0].rotation, *previous_rotation);
      const double angle1 = rotationAngleBetween(candidates[1].rotation, *previous_rotation);
      chosen = angle1 < angle0 ? 1 : 0;
      solution->chosen_by_previous_pose = true;
    }
    const Candidate& alternative = candidates[1 - chosen];
    solution->has_alternative = true;
    solution->alternative_rotation = alternative.rotation;
    solution->alternative_translation = alternative.translation;
    solution->alternative_rms_px = alternative.rms;
  }
  solution->pose.rotation = candidates[chosen].rotation;
  solution->pose.translation = candidates[chosen].translation;
  refineWithCovariance(camera, model_points, image_points, solution);
  return true;
}

void PlanarPnpSolver::refineWithCovariance(const CameraIntrinsics& camera, const std::vector<Eigen::Vector3d>& model_points,
                                           const std::vector<Eigen::Vector2d>& image_points,
                                           PlanarPnpSolution* solution) const {
  refinePoseLevenbergMarquardt(camera, model_points, image_points, kMaxRefinementIterations, &solution->pose.rotation,
                               &solution->pose.translation);
  solution->reprojection_rms_px =
      reprojectionRms(camera, solution->pose.rotation, solution->pose.translation, model_points, image_points);
  // Residual variance per coordinate with 6 parameters fitted, floored.
  const double dof = std::max(1.0, 2.0 * static_cast<double>(model_points.size()) - 6.0);
  const double residual_variance =
      solution->reprojection_rms_px * solution->reprojection_rms_px * 2.0 * static_cast<double>(model_points.size()) /
      dof / 2.0;
  const double variance = std::max(residual_variance, min_pixel_sigma_px_ * min_pixel_sigma_px_);
  leastSquaresPoseCovariance(camera, solution->pose.rotation, solution->pose.translation, model_points, variance,
                             &solution->pose.covariance);
}
}  // namespace mono
}  // namespace docking_perception
