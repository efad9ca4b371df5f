// Direct (intensity-based) alignment of the textured face (issue 11): when blur leaves too few corners
// for the feature matcher, the face's pixels still carry its position. Given a prior (the tracked pose
// predicted to this image, or an external position hint with a few yaw hypotheses), the model texture is
// aligned with the image by ECC (enhanced correlation coefficient, cv::findTransformECC) over a
// homography, coarse to fine on Gaussian pyramids of the image and of the texture resampled to the face's
// apparent size. ECC maximises a zero-mean normalised correlation, so gain and offset (auto exposure) do
// not matter; it only needs the prior within its basin. At the coarsest level the template is first slid
// over the window (normalised correlation, whole pixels, a quarter of the face each way), and a level
// whose homography ECC gives up (near-singular on a small smooth template) is fitted affine instead. The result is a grid of face points mapped through the homography, i.e. correspondences that
// the estimator's PnP and consistency checks use like the feature matcher's.
//
// Honesty: the final correlation must reach min_correlation, the homography must keep the face convex
// and in view, and the pixel sigma of the grid points comes from the fit itself (residual over the
// template's gradient energy, per independent pixel), so the covariance grows with noise and blur.
#pragma once

#include <opencv2/core.hpp>
#include <string>
#include <vector>

#include "docking_perception/mono/mono_pose_settings.h"
#include "docking_perception/mono/pose_types.h"
#include "docking_perception/mono/target_model.h"

namespace docking_perception {
namespace mono {

// DirectAlignmentParams (keys direct_*) is declared in settings/mono_pose.yaml (generated header).

struct DirectAlignment {
  bool found = false;
  std::string status;                            // why not found
  double correlation = -1.0;                     // final ECC correlation
  cv::Matx33d homography = cv::Matx33d::eye();   // texture pixel -> image pixel
  std::vector<cv::Point2f> texture_points;       // the grid, texture pixels
  std::vector<cv::Point2f> image_points;         // the grid through the homography, image pixels
  std::vector<cv::Point2f> face_outline;         // texture corners through the homography
  double pixel_sigma_px = 0.0;                   // 1-sigma of each grid point implied by the fit (image px)
  double image_scale = 1.0;                      // image pixels per working pixel
};

// Texture pixel -> image pixel for a pose (camera <- target) of the face plane (texture_to_face: the
// model's TargetModel::textureToFace()).
cv::Matx33d faceHomography(const Eigen::Matrix3d& texture_to_face, const CameraIntrinsics& camera,
                           const PoseWithCovariance& pose);
inline cv::Matx33d faceHomography(const TargetModel& model, const CameraIntrinsics& camera,
                                  const PoseWithCovariance& pose) {
  return faceHomography(model.textureToFace(), camera, pose);
}

class DirectFaceAligner {
 public:
  DirectFaceAligner() = default;
  DirectFaceAligner(const TargetModel& model, const DirectAlignmentParams& params);
  void setParams(const DirectAlignmentParams& params) { params_ = params; }
  const DirectAlignmentParams& params() const { return params_; }
  bool ready() const { return !texture_.empty(); }

  // Aligns from an initial homography (texture pixel -> image pixel). coarse_only: stop one level above
  // the finest (cheap scoring of hypotheses; the correlation is that level's). template_blur_px: the
  // image's blur (Gaussian sigma, image px) where it has been measured; the template is blurred alike,
  // so that the correlation compares like with like.
  DirectAlignment align(const cv::Mat& gray, const cv::Matx33d& initial, bool coarse_only = false,
                        double template_blur_px = 0.0) const;
  // The same from a pose (camera <- target).
  DirectAlignment align(const cv::Mat& gray, const CameraIntrinsics& camera, const PoseWithCovariance& initial) const;

 private:
  struct Frames;
  bool makeFrames(const cv::Mat& gray, const cv::Matx33d& initial, double template_blur_px, Frames* frames,
                  std::string* why) const;
  // Checks the aligned face (in view, convex, size, correlation) and adds the grid and its pixel sigma.
  DirectAlignment finish(const cv::Matx33d& initial, const Frames& frames, const cv::Mat& templ, const cv::Mat& image,
                         const cv::Matx33f& warp, DirectAlignment result) const;

  DirectAlignmentParams params_;
  cv::Mat texture_;  // 8-bit gray
  TargetModel model_;
};

}  // namespace mono
}  // namespace docking_perception
