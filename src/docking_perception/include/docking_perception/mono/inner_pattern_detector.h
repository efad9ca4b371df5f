// The inner pattern: a small AprilTag printed near the port (target.yaml `inner_pattern`) that the
// visible camera still sees, in focus enough, down to contact, where the face no longer fits in the
// image. InnerPatternDetector finds it (libapriltag through TagDetector), then refines every corner of
// the tag's cell grid (where the cells around a grid point are not one colour or a straight edge:
// 30-60 points for tag36h11) to sub-pixel from the tag's homography (cv::cornerSubPix), and takes the
// pose of frame `target` from them (IPPE + Levenberg-Marquardt, PlanarPnpSolver) with the Gauss-Newton
// covariance scaled by their residuals (floored). ROS-free.
#pragma once

#include <Eigen/Core>
#include <array>
#include <memory>
#include <opencv2/core.hpp>
#include <string>

#include "docking_perception/mono/apriltag_pose.h"
#include "docking_perception/mono/planar_pnp_solver.h"
#include "docking_perception/mono/pose_types.h"

namespace docking_perception {
namespace mono {

// Whether and where it is used (inner_pattern_enabled, inner_pattern_use_range_m) is the estimator's choice
// (settings/mono_pose.yaml); the gates of a tag pose here are constants of the method (the .cpp says why).

struct InnerPatternResult {
  bool valid = false;
  std::string status;                  // why not valid
  PoseWithCovariance pose;             // camera <- target (the port)
  double reprojection_rms_px = 0.0;
  double decision_margin = 0.0;
  int hamming = 0;
  std::array<Eigen::Vector2d, 4> corners_px{};  // the black square's corners (when detected)
  int candidate_points = 0;            // grid corners of the tag
  int pose_points = 0;                 // of them, refined and used by the pose
  // What the estimator's covariance model needs (modelPnpCovariance): the fitted points in `target`
  // and IPPE's solutions. `pose.covariance` here is the fit's alone (residuals, floored).
  std::vector<Eigen::Vector3d> model_points;
  PlanarPnpSolution pnp;
  double processing_time_ms = 0.0;     // CPU time of detection and pose
};

class InnerPatternDetector {
 public:
  // The floor of the corner noise that scales a tag pose's covariance (a fit of 30-40 corners within
  // 0.1 px must not claim a tenth of a millimetre).
  static constexpr double kMinPixelSigmaPx = 0.5;

  // Throws TagError for an unsupported tag.
  explicit InnerPatternDetector(const TagSpec& tag);
  const TagSpec& tag() const { return tag_; }
  // The grid corners the pose uses, in frame `target`.
  const std::vector<Eigen::Vector3d>& gridPoints() const { return grid_target_m_; }

  // gray: 8-bit, rectified, the size of camera. previous_rotation: the last trusted orientation
  // (camera <- target) to settle IPPE's ambiguity, or nullptr. roi: where to look (empty: everywhere).
  InnerPatternResult detect(const cv::Mat& gray, const CameraIntrinsics& camera,
                            const Eigen::Matrix3d* previous_rotation, const cv::Rect& roi = cv::Rect());

 private:
  // Refines the grid corners predicted by the 4 detected corners; fills model / image points.
  void refineGrid(const cv::Mat& gray, const std::array<Eigen::Vector2d, 4>& corners,
                  std::vector<Eigen::Vector3d>* model, std::vector<Eigen::Vector2d>* image) const;

  TagSpec tag_;
  // Grid corners as (x, y) in apriltag's tag frame (m; x right, y down as printed) and in `target`.
  std::vector<Eigen::Vector2d> grid_tag_m_;
  std::vector<Eigen::Vector3d> grid_target_m_;
  std::unique_ptr<TagDetector> detector_;
  PlanarPnpSolver pnp_;
};

}  // namespace mono
}  // namespace docking_perception
