// MonoPoseEstimator: one image in, everything mono_pose publishes out (pose with covariance, validity
// and the reason, quality figures, velocities with covariance, and what the debug image draws).
//
// Visible mode: FeatureMatcher finds the face (in the region predicted from the last pose when
// tracking, else, or when that fails, the full frame); the `pnp` solver uses every homography inlier,
// the `paper_5point` solver locates the 5 printed dots where the homography predicts them.
// IR mode: LedPatternDetector finds the LED blobs and the pattern; both solvers then use the 5 LEDs
// (`pnp` as IPPE + LM over 5 points). Every pose passes the same checks: reprojection error, a finite range,
// and the face turned towards the camera.
#pragma once

#include <limits>
#include <memory>
#include <optional>
#include <opencv2/core.hpp>
#include <string>
#include <vector>

#include "docking_perception/mono/collinear_five_point_solver.h"
#include "docking_perception/mono/dark_dot_locator.h"
#include "docking_perception/mono/face_alignment.h"
#include "docking_perception/mono/face_search.h"
#include "docking_perception/mono/feature_matcher.h"
#include "docking_perception/mono/inner_pattern_detector.h"
#include "docking_perception/mono/led_pattern_detector.h"
#include "docking_perception/mono/mono_pose_settings.h"
#include "docking_perception/mono/planar_pnp_solver.h"
#include "docking_perception/mono/pose_consistency.h"
#include "docking_perception/mono/pose_types.h"
#include "docking_perception/mono/reject_reason.h"
#include "docking_perception/mono/stages.h"
#include "docking_perception/mono/target_model.h"
#include "docking_perception/mono/velocity_estimators.h"

namespace docking_perception {
namespace mono {

enum class MonoMode { kVisible, kIr };
enum class PoseSolverType { kPaperFivePoint, kPnp };
enum class VelocityMethod { kFilter, kFrameDifference };

// Names used in parameters and in TargetEstimate.solver: "visible" | "ir", "paper_5point" | "pnp",
// "kalman" | "frame_difference". parse* return false for an unknown name.
bool parseMonoMode(const std::string& name, MonoMode* mode);
bool parsePoseSolver(const std::string& name, PoseSolverType* solver);
bool parseVelocityMethod(const std::string& name, VelocityMethod* method);
std::string toString(MonoMode mode);
std::string toString(PoseSolverType solver);
std::string toString(VelocityMethod method);

// MonoPoseParams, the estimator's settings (its components' nested), is declared in settings/mono_pose.yaml
// (generated header). publish_filtered_orientation: the published orientation is the velocity filter's
// posterior at the image's stamp once the filter has fused at least two poses since its last restart and
// accepted this one; otherwise the image's own. Single images under blur scatter by degrees about the truth,
// frame to frame; their fused orientation does not. The position stays the image's own: a turning camera
// moves the target on a curve in its frame, which a constant-velocity filter follows with a lag.
// predict_face_when_tracking (visible): the face refined where the filter's predicted pose puts it
// (FeatureMatcher::matchAtPrediction), without the feature search, when the last image claimed its
// orientation; the search runs when fewer than half of the refined points hold,
// or the pose fails a check. use_direct_alignment (visible): when the features find no face and a prior
// exists (the tracked pose, or a region/position hint), the texture is aligned with the image directly
// (face_alignment.h).

// The settings' choices as the estimator uses them.
MonoMode modeOf(const MonoPoseParams& params);
PoseSolverType solverOf(const MonoPoseParams& params);
VelocityMethod velocityOf(const MonoPoseParams& params);

// MonoPoseResult::solver when the pose comes from the inner pattern.
constexpr const char* kInnerPatternSolverName = "inner_pattern";

// Throws docking_settings::ConfigError (a std::invalid_argument) naming the first setting its declaration
// does not allow (its key in config/mono_pose_<mode>.yaml, e.g. "fast_threshold"), or two that contradict.
void validate(const MonoPoseParams& params);

struct MonoPoseResult {
  double stamp_s = 0.0;
  bool valid = false;
  // The orientation is claimed (valid and its sigma within max_rotation_sigma_deg); when false on a
  // valid result, only the position (and the velocities) may be used.
  bool orientation_valid = false;
  std::string status;                  // why not valid, or what part is withheld (for people); else empty
  RejectReason reject_reason = RejectReason::kNone;  // the same as a coarse code (for programs)
  Stage stage = Stage::kNone;          // the stage that decided (stages.h) ...
  std::uint8_t stage_outcome = 0;      // ... and its outcome code there (0: passed)
  std::string solver;                  // "paper_5point" or "pnp"
  PoseWithCovariance pose;             // camera <- target: what is published (see publish_filtered_orientation)
  PoseWithCovariance measured_pose;    // this image's own pose (equal to `pose` unless orientation_filtered)
  bool orientation_filtered = false;   // `pose`'s orientation is the velocity filter's posterior
  double range_m = 0.0;
  TwistWithCovariance twist;           // from the selected velocity method
  TwistWithCovariance twist_filter;
  TwistWithCovariance twist_frame_difference;
  std::string velocity_status;         // why the selected velocity is not valid / a note from the filter
  int feature_matches = 0;             // visible: ratio-test matches; IR: LED blobs found
  int feature_inliers = 0;             // visible: homography inliers; IR: 5 when the pattern is found
  int pose_points = 0;                 // points the solver used (visible pnp: refined points)
  double reprojection_error_px = 0.0;  // RMS over the points the solver used
  double processing_time_ms = 0.0;     // CPU time of process()
  bool used_tracking_region = false;   // the predicted region gave the result (no full-frame search)
  bool used_predicted_face = false;    // ... and the face was refined at its predicted place, without features
  bool face_search_skipped = false;    // near contact, the face's search skipped (kFaceRetryEvery)
  cv::Rect search_region;              // where detection ran last (full frame after a fallback)
  bool pnp_ambiguous = false;          // IPPE's two poses were close
  double ambiguity_deg = 0.0;          // the undecided IPPE alternative's angle (0: decided)
  bool used_region_hint = false;       // the external region hint gave the result
  bool found_by_dots = false;          // visible: the face was found from its five printed dots
  int pyramid_level = 0;               // visible: image level of the keypoints (0 full, 1 half resolution)
  double inlier_spread = 0.0;          // visible: hull of the pose points / face area
  double appearance_ncc = -1.0;        // visible: the model at the pose vs the image (median cell NCC)
  double blur_sigma_px = 0.0;          // visible: the image blur that matched the model best; IR: the LED streaks
  // The covariance's scale (variance) from the poses' scatter about the filter (InnovationCovarianceScale).
  double covariance_scale_position = 1.0;
  bool rotation_innovation_checked = false;  // the filter had a recent pose to predict this one from
  double covariance_scale_rotation = 1.0;
  bool used_direct_alignment = false;  // visible: the pose rests on the direct (ECC) alignment, not features
  double direct_correlation = -1.0;    // visible: the direct alignment's final correlation (-1: not tried)
  // For the debug image.
  std::vector<cv::Point2f> matched_points;
  std::vector<cv::Point2f> inlier_points;
  std::vector<cv::Point2f> face_outline;
  std::vector<Eigen::Vector2d> marker_pixels;  // markers / LEDs in model order, when located
  std::vector<Eigen::Vector2d> blob_pixels;    // IR: every LED blob
  // The inner pattern, when it was looked for: why it gave no pose (empty when it did).
  std::string inner_pattern_status;
};

class MonoPoseEstimator {
 public:
  // Throws std::invalid_argument (with the reason) for invalid parameters or intrinsics, or a visible
  // model whose texture yields too few features.
  MonoPoseEstimator(const TargetModel& model, const CameraIntrinsics& camera, const MonoPoseParams& params);

  // New parameters (dynamic_reconfigure); throws std::invalid_argument and keeps the old ones if invalid.
  void setParams(const MonoPoseParams& params);
  const MonoPoseParams& params() const { return params_; }
  // New intrinsics (camera_info changed); throws std::invalid_argument if invalid.
  void setCamera(const CameraIntrinsics& camera);
  const CameraIntrinsics& camera() const { return camera_; }
  const TargetModel& model() const { return model_; }

  // One image (8-bit gray or BGR, rectified, the size of the intrinsics) at a stamp (s).
  MonoPoseResult process(const cv::Mat& image, double stamp_s);
  // Forget the tracking state and velocities.
  void reset();
  // Where the target should be in the next images (e.g. the disparity detector's estimate projected into
  // this camera), at an image stamp: searched before the full frame while not tracking, for
  // region_hint_max_age_s. An empty rect clears it.
  void setRegionHint(const cv::Rect& region, double stamp_s);
  // The same from a 3D position of the target in this camera's frame (the disparity detector's estimate,
  // same optical frame): the square of region_hint_radius_m around it, projected, plus the tracking
  // margin. A position behind the camera or not finite clears the hint. While fresh it also checks the
  // pose: see ConsistencyParams::max_hint_disagreement_fraction.
  void setPositionHint(const Eigen::Vector3d& position_camera, double stamp_s);

  // Near contact, once the face's search failed while the inner pattern gave the pose, the face is searched
  // on every kFaceRetryEvery-th image only: its failing search (20-40 ms) was the chain's worst latency.
  static constexpr int kFaceRetryEvery = 5;

 private:
  // What an IR search over the LED patterns learned, for the reason when none gave a pose.
  struct LedSearch {
    std::string reason;
    bool blob_rejected = false;       // a pattern's blob was merged with a reflection
    bool candidate_unsolved = false;  // a pattern of LED-like blobs gave no plausible pose
  };

  // The stages of process() (stages.h), in order.
  InputOutcome readImage(const cv::Mat& image, cv::Mat* gray, MonoPoseResult* result) const;
  // Near contact (kFaceRetryEvery): this image's face search is skipped.
  FindOutcome skipFaceSearch(MonoPoseResult* result);
  // Find, solve and vet: the face's pose (visible) or the LEDs' (IR); result->valid when it passed them.
  StageOutcome measurePose(const cv::Mat& gray, MonoPoseResult* result);
  // Close range: the inner pattern's pose when the face gave none.
  InnerPatternOutcome applyInnerPattern(const cv::Mat& gray, MonoPoseResult* result);
  // A fresh position hint's range against the pose's (consistency.max_hint_disagreement_fraction); without a
  // fresh hint, a pose at least hint_check_min_range_m away is refused for 1 s after a
  // pose that disagreed.
  HintOutcome checkPositionHint(MonoPoseResult* result);
  // The pose is valid: its covariance scaled by the innovation, and whether its orientation is claimed.
  OrientationOutcome claimOrientation(MonoPoseResult* result);
  // Velocities, the tracking state, and the published (filtered) orientation.
  void trackPose(MonoPoseResult* result);
  // A tracked pose whose position sigma is above consistency.max_position_sigma_fraction of its range is
  // published not valid (kPositionUncertain), though it stays the tracked pose.
  PositionOutcome claimPosition(MonoPoseResult* result) const;

  // Visible: the face at its predicted place, else searched (features, then the direct alignment), then
  // its pose.
  StageOutcome measureVisible(const cv::Mat& gray, const cv::Rect& region, double face_width_px, MonoPoseResult* result);
  // Tracking with a claimed orientation (predict_face_when_tracking): true when the face refined at its
  // predicted place gave a pose that passed; else the result is as it was.
  bool posedAtPredictedFace(const cv::Mat& gray, const cv::Rect& region, MonoPoseResult* result);
  // The face by features in the predicted region and the hint's region, by its five dots, by features in
  // the full frame, then by direct alignment.
  StageOutcome findFace(const cv::Mat& gray, const cv::Rect& region, double face_width_px, FaceMatch* match,
                        double* direct_sigma_px, MonoPoseResult* result);
  // A pose the five dots give and the image's blur measured there: the direct alignment's prior.
  struct DotsPrior {
    PoseWithCovariance pose;
    MarkerPixels dots{};  // where the five dots were found
    double blur_px = 0.0;
  };
  // The direct alignment from the tracked pose, else the dots' pose (dots, may be null), else the hint's
  // position; its face into match.
  void alignFaceDirectly(const cv::Mat& gray, bool hint_fresh, const DotsPrior* dots, FaceMatch* match,
                         double* direct_sigma_px, MonoPoseResult* result);
  // searchFace over the regions (and the full frame), its match and what it tells into result. A match whose
  // inliers span less than min_inlier_spread of the face is not found (the vet would refuse it; the search
  // goes on to the dots and the direct alignment).
  bool findFaceByFeatures(const cv::Mat& gray, const std::vector<SearchRegion>& regions, bool full_frame,
                          FaceMatch* match, MonoPoseResult* result);
  // The face from its five printed dots anywhere in the image, no prior needed: the dots' 5-point patterns,
  // each one's pose, tried in the order of how much the face looks like the model there (the appearance
  // score), the face refined where that pose puts it (as a tracked face is). False (why in *status) when no
  // pattern gives a face; *best_looking is then the pose that looked most like the face, with the blur
  // measured there (the direct alignment's prior), if any pattern solved.
  bool findFaceByDots(const cv::Mat& gray, FaceMatch* match, std::string* status,
                      std::optional<DotsPrior>* best_looking, MonoPoseResult* result) const;
  // The face's pose from a 5-point pattern (dots or LEDs): the closed form, then the least-squares pose it
  // starts; false (with the reason) when either fails or the fit's residual is over max_reprojection_px.
  bool patternPose(const MarkerPixels& pixels, PoseWithCovariance* pose, std::string* reason) const;
  // True when the face's homography puts every dot within its radius of the pixel it was found at.
  bool faceKeepsDots(const cv::Matx33d& face, const MarkerPixels& dots, std::string* reason) const;
  // The best max_patterns 5-dot patterns among the dark dots found at each radius whose size fits that
  // radius.
  std::vector<LedPatternCandidate> dotPatterns(const cv::Mat& gray, size_t max_patterns, std::string* reason) const;
  // The pose from a face match (features or direct alignment): PnP or the 5 dots, then the checks.
  StageOutcome poseFromMatch(const cv::Mat& gray, const FaceMatch& match, double direct_sigma_px, MonoPoseResult* result);
  StageOutcome pnpPoseFromMatch(const cv::Mat& gray, const FaceMatch& match, double direct_sigma_px,
                                MonoPoseResult* result);
  StageOutcome fivePointPoseFromMatch(const cv::Mat& gray, const FaceMatch& match, MonoPoseResult* result);
  void correspondences(const FaceMatch& match, std::vector<Eigen::Vector3d>* model_points,
                       std::vector<Eigen::Vector2d>* image_points) const;
  // paper_5point: where the homography puts printed dot marker_index, and its apparent radius.
  Eigen::Vector2d predictedDot(const cv::Matx33d& homography, int marker_index, double* radius_px) const;
  // IR: the LED patterns in the region (empty: the whole image), best first, until one gives a pose.
  StageOutcome measureIr(const cv::Mat& gray, const cv::Rect& region, MonoPoseResult* result);
  bool poseFromLeds(const cv::Mat& gray, const cv::Rect& roi, LedSearch* search, MonoPoseResult* result) const;
  SolveOutcome solveFivePoint(const MarkerPixels& pixels, MonoPoseResult* result, std::string* reason) const;
  bool checkPose(const PoseWithCovariance& pose, std::string* reason) const;
  HintOutcome hintOutcome(MonoPoseResult* result);
  OrientationOutcome orientationOutcome(MonoPoseResult* result) const;
  // The inner tag's pose (with the covariance model of every PnP pose) where the tracked pose puts it, then
  // in the whole image; not valid when not found.
  InnerPatternResult findInnerTag(const cv::Mat& gray, double* ambiguity_deg, MonoPoseResult* result) const;
  // An external hint is set and at most region_hint_max_age_s from this image's stamp.
  bool hintFresh(double stamp_s) const;
  // The region where the target should appear (empty: search the whole image) and, in visible mode,
  // the face's predicted apparent width.
  cv::Rect predictedRegion(double stamp_s, double* face_width_px) const;
  // The velocity filter's pose at stamp_s while tracking (within filter.max_gap_s of its last pose); false if none.
  bool trackedPose(double stamp_s, PoseWithCovariance* pose) const;
  // The pose expected at stamp_s (the velocity filter's prediction from the last pose; the last pose
  // itself after a gap longer than max_gap_s).
  PoseWithCovariance predictedPose(double stamp_s) const;
  // Tracking: the face at its predicted place (predict_face_when_tracking); found == false when the
  // prediction does not hold.
  FaceMatch matchPredictedFace(const cv::Mat& gray, double stamp_s) const;
  // The face's homography (texture pixel -> image pixel) at a pose, scaled to h(2, 2) = 1.
  cv::Matx33d normalisedFaceHomography(const PoseWithCovariance& pose) const;
  const Eigen::Matrix3d* previousRotation(double stamp_s, Eigen::Matrix3d* storage) const;
  // Feeds the pose to the velocity estimators; true when the filter fused it (or restarted on it).
  bool updateVelocities(MonoPoseResult* result);
  // After the tracking state took this image's pose: the filter's posterior orientation becomes the
  // published one (publish_filtered_orientation); measured_pose keeps the image's own.
  void publishFilteredOrientation(bool fused, MonoPoseResult* result) const;
  void scaleByInnovation(MonoPoseResult* result);
  bool directSearchDue();
  void noteDirectSearch(bool from_hint, bool found);
  // After an image whose face was not found while the inner pattern gave the pose: skip the face's search
  // for the next kFaceRetryEvery - 1 images; any invalid image ends the skipping.
  void updateFaceRetry(bool face_skipped, const MonoPoseResult& result);
  // Where the inner pattern should appear (empty: not tracking, search the whole image).
  cv::Rect predictedInnerPatternRegion(double stamp_s) const;
  // The consistency checks and honest covariance of a visible pose (pose_consistency.h); refused with the
  // reason in result when the pose cannot be trusted.
  // pixel_sigma_px: the noise of the pose points (the PnP residual for features, the fit's own for the
  // direct alignment).
  StageOutcome vetVisiblePose(const cv::Mat& gray, const FaceMatch& match, const std::vector<Eigen::Vector3d>& model_points,
                              const PlanarPnpSolution* pnp, double pixel_sigma_px, MonoPoseResult* result) const;
  // True when a feature match's inliers span at least min_inlier_spread of the face (their hull over the
  // texture's area, into *spread): fewer, bunched, fix no homography (a wrong one fits them as well).
  bool spansFace(const FaceMatch& match, double* spread) const;
  // The direct alignment from the tracked pose or the hint; found == false when no prior or no match.
  DirectAlignment alignDirect(const cv::Mat& gray, bool tracking_prior, bool hint_fresh, double stamp_s) const;
  // A hint's position: the position hint's, or one from the region hint's box.
  Eigen::Vector3d hintPosition() const;
  // paper_5point: the located dots against the homography, and the 5-point pose against the inlier PnP.
  StageOutcome vetFivePointPose(const MarkerPixels& predicted, const MarkerPixels& located, double radius_px,
                                const std::vector<Eigen::Vector3d>& model_points,
                                const std::vector<Eigen::Vector2d>& image_points, MonoPoseResult* result) const;
  // IR: the pose of an identified pattern after its 5-point solve (trial->pose): the blur from the LEDs'
  // streaks, then (pnp) the PnP pose with its covariance and IPPE's undecided alternative. False with the
  // reason when PnP fails or its pose is implausible.
  bool refineIrPose(const MarkerPixels& pixels, double median_streak_px, MonoPoseResult* trial,
                    std::string* reason) const;
  // IR: the LED blobs of a pattern must look like single LEDs.
  bool vetLedBlobs(const std::vector<LedBlob>& blobs, const LedPatternCandidate& candidate, std::string* reason) const;

  TargetModel model_;
  CameraIntrinsics camera_;
  MonoPoseParams params_;
  // params_'s choices, parsed.
  MonoMode mode_ = MonoMode::kVisible;
  PoseSolverType solver_ = PoseSolverType::kPnp;
  VelocityMethod velocity_ = VelocityMethod::kFilter;
  FeatureMatcher matcher_;
  LedPatternDetector led_detector_;
  DarkDotLocator dot_locator_;
  DarkDotFinder dot_finder_;  // visible: the printed dots' radii at the model pyramid's face widths
  CollinearFivePointSolver five_point_solver_;
  PlanarPnpSolver pnp_solver_;
  ConstantVelocityFilter filter_;
  InnovationCovarianceScale innovation_scale_;
  FrameDifferenceVelocity frame_difference_;
  bool tracking_ = false;  // the previous image gave a valid pose
  bool last_orientation_claimed_ = false;  // ... and claimed its orientation
  int direct_failures_ = 0;                // hint-based direct searches failed in a row (capped)
  int direct_backoff_left_ = 0;            // frames to skip before the next hint-based direct search
  PoseWithCovariance last_pose_;
  std::unique_ptr<InnerPatternDetector> inner_pattern_;  // null without an inner pattern or in IR mode
  double last_valid_range_m_ = INFINITY;                 // of the last valid pose (any solver)
  int face_searches_skipped_left_ = 0;  // images whose face search is skipped (kFaceRetryEvery)
  double last_stamp_s_ = 0.0;
  FaceAppearance appearance_;
  int preferred_level_ = 0;  // the pyramid level that found the face last
  cv::Rect hint_region_;
  double hint_stamp_s_ = 0.0;
  bool hint_has_position_ = false;  // the hint came from setPositionHint (else only the region is known)
  Eigen::Vector3d hint_position_ = Eigen::Vector3d::Zero();
  // Image stamp of the last pose that disagreed with a fresh hint; kNoHintDisagreement: none since the
  // last that agreed.
  static constexpr double kNoHintDisagreement = -std::numeric_limits<double>::infinity();
  double last_hint_disagreement_s_ = kNoHintDisagreement;
  DirectFaceAligner direct_aligner_;
};

}  // namespace mono
}  // namespace docking_perception
