// General PnP over all matched points of the planar target face: IPPE (cv::solvePnPGeneric) gives the
// two poses a plane seen from a distance cannot tell apart; the lower reprojection error wins, unless
// the two are close, where the one nearer the previous pose wins. The winner is refined with
// Levenberg-Marquardt (refinePoseLevenbergMarquardt: OpenCV's solvePnPRefineLM spent ~4 M instructions a
// frame on its general camera model's Jacobians) and gets a Gauss-Newton covariance.
#pragma once

#include <Eigen/Core>
#include <string>
#include <vector>

#include "docking_perception/mono/pose_types.h"

namespace docking_perception {
namespace mono {

struct PlanarPnpParams {
  // The two IPPE solutions are "close" (ambiguous) when the larger reprojection error is below
  // ambiguity_ratio times the smaller, or both are below ambiguity_floor_px.
  double ambiguity_ratio = 1.5;
  double ambiguity_floor_px = 0.5;
  // Lower bound of the pixel noise used to scale the covariance (a perfect fit must not claim zero).
  double min_pixel_sigma = 0.2;
};

struct PlanarPnpSolution {
  PoseWithCovariance pose;
  double reprojection_rms_px = 0.0;
  bool ambiguous = false;               // IPPE's two solutions were close
  bool chosen_by_previous_pose = false; // ... and the previous pose decided
  Eigen::Matrix3d alternative_rotation = Eigen::Matrix3d::Identity();  // the other IPPE solution
  Eigen::Vector3d alternative_translation = Eigen::Vector3d::Zero();
  double alternative_rms_px = 0.0;
  bool has_alternative = false;
};

class PlanarPnpSolver {
 public:
  explicit PlanarPnpSolver(const PlanarPnpParams& params = PlanarPnpParams()) : params_(params) {}
  void setParams(const PlanarPnpParams& params) { params_ = params; }
  const PlanarPnpParams& params() const { return params_; }

  // model_points: coplanar points in frame `target`; image_points: their pixels. At least 4.
  // previous_rotation: the last trusted orientation (camera <- target), or nullptr.
  bool solve(const CameraIntrinsics& camera, const std::vector<Eigen::Vector3d>& model_points,
             const std::vector<Eigen::Vector2d>& image_points, const Eigen::Matrix3d* previous_rotation,
             PlanarPnpSolution* solution, std::string* reason) const;

 private:
  PlanarPnpParams params_;
};

}  // namespace mono
}  // namespace docking_perception
