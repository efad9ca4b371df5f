// General PnP over all matched points of the planar target face: IPPE (cv::solvePnPGeneric) gives the
// two poses a plane seen from a distance cannot tell apart; the lower reprojection error wins, unless
// the two are close, where the one nearer the previous pose wins. The winner is refined with
// Levenberg-Marquardt (refinePoseLevenbergMarquardt: OpenCV's solvePnPRefineLM spent ~4 M instructions a
// frame on its general camera model's Jacobians) and gets a Gauss-Newton covariance.
#pragma once

#include <Eigen/Core>
#include <string>
#include <vector>

#include "docking_perception/mono/mono_pose_settings.h"
#include "docking_perception/mono/pose_types.h"

namespace docking_perception {
namespace mono {

// When IPPE's two poses count as close, so that the previous pose decides between them: the larger RMS
// residual within ambiguity_ratio x the smaller, or both within ambiguity_floor_px (the face's pixel noise
// floor). Constants of the method, not settings: they compare residuals with each other and with the
// refinement's noise, which no rig changes. The inner pattern's 30-40 grid corners use a lower floor.
struct PlanarPnpParams {
  double ambiguity_ratio = 1.5;
  double ambiguity_floor_px = 0.5;
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
  // min_pixel_sigma_px: the lower bound of the pixel noise that scales the covariance (a perfect fit must
  // not claim zero): the caller's (mono_pose's min_pixel_sigma, the inner pattern's own).
  explicit PlanarPnpSolver(const PlanarPnpParams& params = PlanarPnpParams(), double min_pixel_sigma_px = 0.2)
      : params_(params), min_pixel_sigma_px_(min_pixel_sigma_px) {}
  void setParams(const PlanarPnpParams& params, double min_pixel_sigma_px) {
    params_ = params;
    min_pixel_sigma_px_ = min_pixel_sigma_px;
  }
  const PlanarPnpParams& params() const { return params_; }
  double minPixelSigma() const { return min_pixel_sigma_px_; }

  // model_points: coplanar points in frame `target`; image_points: their pixels. At least 4.
  // previous_rotation: the last trusted orientation (camera <- target), or nullptr.
  bool solve(const CameraIntrinsics& camera, const std::vector<Eigen::Vector3d>& model_points,
             const std::vector<Eigen::Vector2d>& image_points, const Eigen::Matrix3d* previous_rotation,
             PlanarPnpSolution* solution, std::string* reason) const;

 private:
  // The chosen pose refined by Levenberg-Marquardt, its RMS and its Gauss-Newton covariance.
  void refineWithCovariance(const CameraIntrinsics& camera, const std::vector<Eigen::Vector3d>& model_points,
                            const std::vector<Eigen::Vector2d>& image_points, PlanarPnpSolution* solution) const;

  PlanarPnpParams params_;
  double min_pixel_sigma_px_;
};

}  // namespace mono
}  // namespace docking_perception
