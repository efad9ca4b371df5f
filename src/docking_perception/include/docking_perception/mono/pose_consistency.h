// Checks that decide whether a monocular pose can be trusted, and the covariance it is published with
// (issue 11: honest confidence). Each check answers with a RejectReason; the estimator runs them after
// its solver and reports the first failure as invalid.
//
// - Inlier spread: the convex hull of the points the pose rests on, as a fraction of the face. Points
//   bunched in one corner (a glint or a card over the rest) constrain the tilt badly, and a wrong
//   homography from a few clustered matches looks exactly like that.
// - Appearance: the model texture warped into the image at the *estimated pose*, compared with the image
//   by normalised cross-correlation in cells over the face (median over cells; saturated pixels left
//   out, so a glint costs only its own cells). The template is blurred with a few sigmas and the best
//   is kept: that sigma is also the estimate of the image's blur, which scales the covariance.
// - Covariance: the solver's Gauss-Newton covariance assumes independent pixel errors at the residual
//   level; blur makes the errors larger and correlated, so the pixel sigma is scaled by
//   (1 + blur_gain * blur sigma), and a floor (a fraction of the range for position, an angle for
//   orientation) covers what residuals cannot see (the refinement's bias, the model's print). The
//   floor and the gain were fitted on the stress harness's tuning seeds (README).
// - IPPE ambiguity: when the two planar solutions both fit and no previous pose decided, the chosen one
//   is kept only if the other is close; its difference is then added to the covariance.
// - LED blobs (IR): blobs of the pattern that are much larger than the others or elongated are a
//   reflection or a second source merged with an LED; their centroid is pulled off the LED.
#pragma once

#include <algorithm>
#include <opencv2/core.hpp>
#include <string>
#include <vector>

#include "docking_perception/mono/mono_pose_settings.h"
#include "docking_perception/mono/planar_pnp_solver.h"
#include "docking_perception/mono/pose_types.h"
#include "docking_perception/mono/reject_reason.h"
#include "docking_perception/mono/target_model.h"

namespace docking_perception {
namespace mono {

// ConsistencyParams, the checks' and the covariance model's settings, is declared in settings/mono_pose.yaml
// (generated header).

// The covariance floor, a constant of the model (fitted on the stress harness's tuning seeds 100-139): each
// position axis' sigma at least 0.2 % of the range, each rotation axis' 0.3 deg.
constexpr double kPositionFloorFraction = 0.002;
constexpr double kRotationFloorDeg = 0.3;
// Adds that floor to a pose covariance (position block at `range_m`).
void addCovarianceFloor(double range_m, Matrix6d* covariance);

// Area of the convex hull of texture points / texture area (0 for fewer than 3 points).
double inlierSpread(const std::vector<cv::Point2f>& texture_points, const cv::Size& texture_size);

struct AppearanceScore {
  double median_ncc = -1.0;    // median over the face cells with texture; -1 when none
  double blur_sigma_px = 0.0;  // the template blur that matched best (image px)
  int cells = 0;               // cells that took part
};

class FaceAppearance {
 public:
  FaceAppearance() = default;
  explicit FaceAppearance(const TargetModel& model);
  bool ready() const { return !pyramid_.empty(); }
  // The model at the pose (camera <- target) compared with the image (8-bit gray).
  AppearanceScore score(const cv::Mat& gray, const CameraIntrinsics& camera, const PoseWithCovariance& pose) const;

 private:
  std::vector<cv::Mat> pyramid_;  // the texture halved repeatedly (level 0 = full size)
  Eigen::Matrix3d texture_to_face_ = Eigen::Matrix3d::Identity();
};

// The covariance model: Gauss-Newton covariance of the pose points at the pixel sigma
// max(residual sigma, min_pixel_sigma) * (1 + blur_gain * blur), plus the floor.
Matrix6d honestCovariance(const CameraIntrinsics& camera, const PoseWithCovariance& pose,
                          const std::vector<Eigen::Vector3d>& model_points, double residual_rms_px,
                          double min_pixel_sigma, double blur_sigma_px, const ConsistencyParams& params);

// Whether the pose's orientation may be claimed: the largest rotation sigma (the rotation block's largest
// eigenvalue) within max_rotation_sigma_deg. If not, *note says so (for people).
bool orientationClaimed(const PoseWithCovariance& pose, const ConsistencyParams& params, std::string* note);

// Whether the pose's position may be claimed: the largest position sigma (the position block's largest
// eigenvalue) within max_position_sigma_fraction of the range, where the pose is nearer than
// position_sigma_check_max_range_m (when set). If not, *note says so (for people).
bool positionClaimed(const PoseWithCovariance& pose, const ConsistencyParams& params, std::string* note);

// The covariance model predicts the pixel noise from the residuals and the blur; it cannot see noise that
// all the points share (a blurred face's points move together, so their residuals stay small while the
// pose jitters by degrees). The poses' scatter about the constant-velocity filter's prediction can: the
// normalized innovation chi^2 (measurement and prediction covariances added) has expectation 1 per
// degree of freedom. This keeps its running mean over ~window frames, for the position and the rotation
// block separately, and scales the covariance by it where it is above 1 (never below the model).
class InnovationCovarianceScale {
 public:
  explicit InnovationCovarianceScale(double window_frames = 10.0) { setWindow(window_frames); }
  void setWindow(double window_frames);
  // The measured pose (its covariance from the model, before scaling) against the prediction for its stamp.
  // Returns this frame's rotation chi^2 (3 dof, not divided; NaN when it cannot be formed).
  double update(const PoseWithCovariance& measured, const PoseWithCovariance& predicted);
  // Scales the position block by positionScale(), the rotation block by rotationScale() (variances).
  void apply(Matrix6d* covariance) const;
  double positionScale() const { return std::max(1.0, position_mean_); }
  double rotationScale() const { return std::max(1.0, rotation_mean_); }
  void reset();

 private:
  double weight_ = 0.0;  // of the newest frame in the running mean; 0: off
  double position_mean_ = 1.0;
  double rotation_mean_ = 1.0;
};

// The angle (deg) from a PnP pose (rotation) to IPPE's other solution when nothing tells the two apart:
// the other's extra squared residual over all points, in units of the pixel variance, plus
// extra_evidence_chi2 (what else favours the chosen solution, in the same units), is below
// params.ambiguity_chi2, and no claimed orientation tracked to this frame (claimed_previous, may be null)
// is nearer the chosen solution than the other. 0 when decided. pixel_sigma_px: the points' noise (floored).
double undecidedAlternativeDeg(const PlanarPnpSolution& pnp, const Eigen::Matrix3d* claimed_previous,
                               size_t point_count, double rms_px, double pixel_sigma_px,
                               const Eigen::Matrix3d& rotation, const ConsistencyParams& params,
                               double extra_evidence_chi2 = 0.0);

// What a pose's history says about its orientation, for IPPE's choice.
struct OrientationHistory {
  // A claimed orientation tracked to this frame: decides alone when it is nearer the chosen solution.
  const Eigen::Matrix3d* claimed = nullptr;
  // The velocity filter's prediction for this frame, claimed or not: its rotation covariance weighs it.
  // How much better it fits the chosen solution than the other (the difference of their squared
  // Mahalanobis distances, prediction and measurement covariances added) adds to the residuals' evidence.
  const PoseWithCovariance* tracked = nullptr;
};

// The squared Mahalanobis distance of `other` from the tracked orientation minus that of `chosen` (the
// rotation blocks of tracked.covariance and measured_rotation_covariance added); 0 when not invertible.
double trackedOrientationEvidence(const PoseWithCovariance& tracked, const Eigen::Matrix3d& measured_rotation_covariance,
                                  const Eigen::Matrix3d& chosen, const Eigen::Matrix3d& other);

// The covariance model of every planar PnP pose (the face's, the IR pattern's, the inner pattern's), in one
// place: honestCovariance at pixel_sigma_px, plus IPPE's other solution (addAlternative) when nothing
// decides between the two (undecidedAlternativeDeg with the floored pixel sigma and the history's
// evidence). Sets pose->covariance; returns the undecided alternative's angle, deg (0: decided).
// rms_px: the pose's reprojection RMS.
double modelPnpCovariance(const CameraIntrinsics& camera, const PlanarPnpSolution& pnp, const OrientationHistory& history,
                          const std::vector<Eigen::Vector3d>& model_points, double rms_px, double pixel_sigma_px,
                          double min_pixel_sigma, double blur_sigma_px, const ConsistencyParams& params,
                          PoseWithCovariance* pose);

// Adds (scale_bias_px / sqrt(projected face area, px^2) x range)^2 along the line of sight to the pose's
// position covariance (ConsistencyParams::face_scale_bias_px). face_corners in the target frame.
void addFaceScaleBias(const CameraIntrinsics& camera, const std::vector<Eigen::Vector3d>& face_corners,
                      double scale_bias_px, PoseWithCovariance* pose);

// Adds the outer product of the difference to another pose (IPPE's other solution) to a covariance.
void addAlternative(const PoseWithCovariance& chosen, const Eigen::Matrix3d& other_rotation,
                    const Eigen::Vector3d& other_translation, Matrix6d* covariance);

}  // namespace mono
}  // namespace docking_perception
