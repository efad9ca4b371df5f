#include "docking_perception/mono/mono_pose_estimator.h"

#include <algorithm>
#include <cmath>
#include <opencv2/imgproc.hpp>
#include <stdexcept>

#include "docking_settings/config_error.h"
#include "docking_settings/setting_info.h"

namespace docking_perception {
namespace mono {
namespace {

// ---- Constants of the method: not settings, since no rig changes them; each says what it guards.
// A prediction is kept when at least half of the refined points tried hold (else: the feature search).
constexpr double kPredictedFaceMinKeptFraction = 0.5;
// Of an image's orientation error (1 sigma), the part that persists from image to image (a tilt bias that
// moves with the blur) and so does not average out in the filter: it stays in the published covariance.
constexpr double kPersistentOrientationFraction = 0.5;
// IR: the streak sigma of a still LED spot; streaks beyond it are motion blur (covariance_blur_gain).
constexpr double kStillLedStreakPx = 0.8;
// IR: a pattern blob larger than 2.5 x the median of the five, or elongated beyond 1.8 (principal axes),
// is merged with a reflection, its centroid pulled off the LED. Without the two (make ablate, rule
// led_merged_blob, stress report seeds 640:40): one confidently wrong IR pose.
constexpr double kMaxLedAreaRatio = 2.5;
constexpr double kMaxLedElongation = 1.8;
// A far pose refused against stereo's range keeps far poses without a fresh hint refused this long (the
// scale bias lasts seconds), and one with a fresh hint must come within half the first refusal's limit to
// be trusted again (stereo's own range is ~2 % off).
constexpr double kHintDisagreementHoldS = 1.0;
constexpr double kHintRecoveryShareOfLimit = 0.5;
// paper_5point (the paper's method, kept for comparison): a dot farther than 0.6 dot radii from where the
// face's homography puts it is not the dot; a 5-point pose 5 deg from the face's PnP pose is refused.
constexpr double kMaxDotOffsetRadii = 0.6;
constexpr double kMaxSolverDisagreementDeg = 5.0;

// Marks the result refused at outcome's stage: the code for programs (stage, reject_reason), the reason for
// people (status). Returns the outcome.
StageOutcome refuse(MonoPoseResult* result, StageOutcome outcome, RejectReason reason, const std::string& status) {
  result->stage = outcome.stage;
  result->stage_outcome = outcome.code;
  result->reject_reason = reason;
  result->status = status;
  return outcome;
}

// A stage's outcome into the result: a code other than 0 decides (until a later stage decides).
template <typename Outcome>
bool record(MonoPoseResult* result, Stage stage, Outcome code) {
  if (code == Outcome{}) return true;
  result->stage = stage;
  result->stage_outcome = static_cast<std::uint8_t>(code);
  return false;
}

bool record(MonoPoseResult* result, StageOutcome outcome) {
  if (outcome.passed()) return true;
  result->stage = outcome.stage;
  result->stage_outcome = outcome.code;
  return false;
}

RejectReason rejectReasonOf(SolveOutcome outcome) {
  switch (outcome) {
    case SolveOutcome::kReprojection: return RejectReason::kReprojection;
    case SolveOutcome::kImplausible: return RejectReason::kImplausiblePose;
    case SolveOutcome::kDotNotLocated: return RejectReason::kDotAppearance;
    case SolveOutcome::kSolverFailed:
    case SolveOutcome::kPassed: break;
  }
  return RejectReason::kSolverFailed;
}

Eigen::Vector2d applyHomography(const cv::Matx33d& h, const Eigen::Vector2d& p) {
  const cv::Vec3d q = h * cv::Vec3d(p.x(), p.y(), 1.0);
  return {q[0] / q[2], q[1] / q[2]};
}

}  // namespace

bool parseMonoMode(const std::string& name, MonoMode* mode) {
  if (name == "visible") *mode = MonoMode::kVisible;
  else if (name == "ir") *mode = MonoMode::kIr;
  else return false;
  return true;
}

bool parsePoseSolver(const std::string& name, PoseSolverType* solver) {
  if (name == "paper_5point") *solver = PoseSolverType::kPaperFivePoint;
  else if (name == "pnp") *solver = PoseSolverType::kPnp;
  else return false;
  return true;
}

bool parseVelocityMethod(const std::string& name, VelocityMethod* method) {
  if (name == "kalman") *method = VelocityMethod::kFilter;
  else if (name == "frame_difference") *method = VelocityMethod::kFrameDifference;
  else return false;
  return true;
}

std::string toString(MonoMode mode) { return mode == MonoMode::kVisible ? "visible" : "ir"; }
std::string toString(PoseSolverType solver) {
  return solver == PoseSolverType::kPnp ? "pnp" : "paper_5point";
}
std::string toString(VelocityMethod method) {
  return method == VelocityMethod::kFilter ? "kalman" : "frame_difference";
}

// The printed dots' apparent radii where the face is as wide as each model level (the range band the
// pyramid covers).
std::vector<double> dotRadii(const TargetModel& model, const FeatureMatcherParams& features) {
  std::vector<double> radii;
  for (const int width : features.model_widths_px) radii.push_back(width * model.markerRadius() / model.faceWidth());
  return radii;
}

MonoMode modeOf(const MonoPoseParams& params) {
  MonoMode mode = MonoMode::kVisible;
  parseMonoMode(params.mode, &mode);
  return mode;
}

PoseSolverType solverOf(const MonoPoseParams& params) {
  PoseSolverType solver = PoseSolverType::kPnp;
  parsePoseSolver(params.solver, &solver);
  return solver;
}

VelocityMethod velocityOf(const MonoPoseParams& params) {
  VelocityMethod method = VelocityMethod::kFilter;
  parseVelocityMethod(params.velocity_method, &method);
  return method;
}

void validate(const MonoPoseParams& p) {
  using docking_settings::ConfigError;
  using docking_settings::ConfigProblem;
  docking_settings::validateSettings(p);
  if (p.features.model_widths_px.empty()) throw ConfigError("model_widths_px", ConfigProblem::kInvalid, "is empty");
}

MonoPoseEstimator::MonoPoseEstimator(const TargetModel& model, const CameraIntrinsics& camera,
                                     const MonoPoseParams& params)
    : model_(model),
      camera_(camera),
      params_(params),
      mode_(modeOf(params)),
      solver_(solverOf(params)),
      velocity_(velocityOf(params)),
      matcher_(params.features),
      led_detector_(model.markers(), params.leds),
      dot_finder_(dotRadii(model, params.features)),
      five_point_solver_(model.markers()),
      pnp_solver_(PlanarPnpParams(), params.min_pixel_sigma),
      filter_(params.filter),
      innovation_scale_(params.consistency.innovation_window_frames),
      frame_difference_(params.filter.max_gap_s) {
  validate(params);
  std::string reason;
  if (!camera.isValid(&reason)) throw std::invalid_argument("camera intrinsics: " + reason);
  if (mode_ == MonoMode::kVisible) {
    if (!model.hasTexture()) throw std::invalid_argument("visible mode needs the target texture");
    if (!matcher_.buildModel(model.textureGray(), &reason)) throw std::invalid_argument(reason);
    if (model.hasInnerPattern()) inner_pattern_ = std::make_unique<InnerPatternDetector>(model.innerPattern());
  }
  appearance_ = FaceAppearance(model);
  if (model.hasTexture()) direct_aligner_ = DirectFaceAligner(model, params.direct);
}

void MonoPoseEstimator::setParams(const MonoPoseParams& params) {
  validate(params);
  if (modeOf(params) != mode_) {
    if (modeOf(params) == MonoMode::kVisible) {
      if (!model_.hasTexture()) throw std::invalid_argument("visible mode needs the target texture");
      matcher_ = FeatureMatcher(params.features);
      std::string reason;
      if (!matcher_.buildModel(model_.textureGray(), &reason)) throw std::invalid_argument(reason);
    }
    reset();
  }
  params_ = params;
  mode_ = modeOf(params);
  solver_ = solverOf(params);
  velocity_ = velocityOf(params);
  if (model_.hasTexture()) direct_aligner_ = DirectFaceAligner(model_, params.direct);
  matcher_.setParams(params.features);
  dot_finder_ = DarkDotFinder(dotRadii(model_, params.features));
  led_detector_.setParams(params.leds);
  pnp_solver_.setParams(PlanarPnpParams(), params.min_pixel_sigma);
  filter_.setParams(params.filter);
  frame_difference_.setMaxGap(params.filter.max_gap_s);
  innovation_scale_.setWindow(params.consistency.innovation_window_frames);
}

void MonoPoseEstimator::setCamera(const CameraIntrinsics& camera) {
  std::string reason;
  if (!camera.isValid(&reason)) throw std::invalid_argument("camera intrinsics: " + reason);
  camera_ = camera;
}

void MonoPoseEstimator::setRegionHint(const cv::Rect& region, double stamp_s) {
  hint_region_ = region & cv::Rect(0, 0, camera_.width, camera_.height);
  hint_stamp_s_ = stamp_s;
  hint_has_position_ = false;
}

void MonoPoseEstimator::setPositionHint(const Eigen::Vector3d& position_camera, double stamp_s) {
  const double z = position_camera.z();
  if (!position_camera.allFinite() || !(z > 0.0)) {
    setRegionHint(cv::Rect(), stamp_s);
    return;
  }
  const double u = camera_.cx + camera_.fx * position_camera.x() / z;
  const double v = camera_.cy + camera_.fy * position_camera.y() / z;
  const double half_u = camera_.fx * params_.region_hint_radius_m / z + params_.tracking_margin_px;
  const double half_v = camera_.fy * params_.region_hint_radius_m / z + params_.tracking_margin_px;
  const cv::Rect region(cv::Point(static_cast<int>(std::floor(u - half_u)), static_cast<int>(std::floor(v - half_v))),
                        cv::Point(static_cast<int>(std::ceil(u + half_u)), static_cast<int>(std::ceil(v + half_v))));
  setRegionHint(region, stamp_s);
  hint_has_position_ = true;
  hint_position_ = position_camera;
}

void MonoPoseEstimator::reset() {
  tracking_ = false;
  last_valid_range_m_ = INFINITY;
  face_searches_skipped_left_ = 0;
  preferred_level_ = 0;
  filter_.reset();
  frame_difference_.reset();
  innovation_scale_.reset();
  direct_failures_ = 0;
  direct_backoff_left_ = 0;
}

const Eigen::Matrix3d* MonoPoseEstimator::previousRotation(double stamp_s, Eigen::Matrix3d* storage) const {
  // A withheld orientation must not pick the next frame's IPPE solution: that would turn a coin flip
  // into a claimed orientation.
  if (!tracking_ || !last_orientation_claimed_) return nullptr;
  PoseWithCovariance predicted;
  *storage = filter_.predict(stamp_s, &predicted) ? predicted.rotation : last_pose_.rotation;
  return storage;
}

bool MonoPoseEstimator::trackedPose(double stamp_s, PoseWithCovariance* pose) const {
  if (!tracking_ || !filter_.initialized() || !(stamp_s > filter_.lastStamp()) ||
      stamp_s - filter_.lastStamp() > params_.filter.max_gap_s) {
    return false;
  }
  return filter_.predict(stamp_s, pose);
}

PoseWithCovariance MonoPoseEstimator::predictedPose(double stamp_s) const {
  PoseWithCovariance predicted = last_pose_;
  if (stamp_s > last_stamp_s_ && stamp_s - last_stamp_s_ <= params_.filter.max_gap_s) {
    filter_.predict(stamp_s, &predicted);
  }
  return predicted;
}

cv::Matx33d MonoPoseEstimator::normalisedFaceHomography(const PoseWithCovariance& pose) const {
  const cv::Matx33d homography = faceHomography(model_, camera_, pose);
  return homography * (1.0 / homography(2, 2));
}

FaceMatch MonoPoseEstimator::matchPredictedFace(const cv::Mat& gray, double stamp_s) const {
  return matcher_.matchAtPrediction(gray, normalisedFaceHomography(predictedPose(stamp_s)),
                                    kPredictedFaceMinKeptFraction);
}

cv::Rect MonoPoseEstimator::predictedRegion(double stamp_s, double* face_width_px) const {
  *face_width_px = 0.0;
  if (!params_.use_tracking_region || !tracking_) return cv::Rect();
  const PoseWithCovariance predicted = predictedPose(stamp_s);
  std::vector<Eigen::Vector3d> outline;
  if (mode_ == MonoMode::kVisible) {
    outline = model_.faceCorners();
  } else {
    outline.assign(model_.markers().begin(), model_.markers().end());
  }
  double min_x = 1e9, min_y = 1e9, max_x = -1e9, max_y = -1e9;
  std::vector<Eigen::Vector2d> pixels;
  for (const Eigen::Vector3d& corner : outline) {
    const Eigen::Vector3d p = predicted.rotation * corner + predicted.translation;
    if (p.z() < 0.05) return cv::Rect();  // prediction too close or behind: search everything
    const Eigen::Vector2d pixel = camera_.project(p);
    pixels.push_back(pixel);
    min_x = std::min(min_x, pixel.x());
    min_y = std::min(min_y, pixel.y());
    max_x = std::max(max_x, pixel.x());
    max_y = std::max(max_y, pixel.y());
  }
  if (mode_ == MonoMode::kVisible) {
    // Apparent width of the face (top and bottom edges), to pick the model levels to match against.
    *face_width_px = 0.5 * ((pixels[1] - pixels[0]).norm() + (pixels[2] - pixels[3]).norm());
  }
  const double margin = params_.tracking_margin_px;
  const cv::Rect region(cv::Point(static_cast<int>(std::floor(min_x - margin)), static_cast<int>(std::floor(min_y - margin))),
                        cv::Point(static_cast<int>(std::ceil(max_x + margin)), static_cast<int>(std::ceil(max_y + margin))));
  const cv::Rect clipped = region & cv::Rect(0, 0, camera_.width, camera_.height);
  // A region covering most of the frame saves nothing; an empty one means the target left the view.
  if (clipped.area() <= 0 || clipped.area() > 0.8 * camera_.width * camera_.height) return cv::Rect();
  return clipped;
}

bool MonoPoseEstimator::checkPose(const PoseWithCovariance& pose, std::string* reason) const {
  // Every failure here is an implausible pose (RejectReason::kImplausiblePose).
  const double range = pose.translation.norm();
  if (!std::isfinite(range)) {
    *reason = "range not finite";
    return false;
  }
  // The face normal (+x of `target`) must point back at the camera, else we would be looking at the
  // back of the face: a wrong solution.
  const Eigen::Vector3d normal = pose.rotation.col(0);
  if (normal.dot(pose.translation) >= 0.0) {
    *reason = "pose shows the back of the face";
    return false;
  }
  if (!pose.covariance.allFinite()) {
    *reason = "covariance is not finite";
    return false;
  }
  return true;
}

SolveOutcome MonoPoseEstimator::solveFivePoint(const MarkerPixels& pixels, MonoPoseResult* result,
                                               std::string* reason) const {
  FivePointSolution solution;
  Matrix6d covariance;
  // First the pose (for the residual), then the covariance scaled by the residual variance (5 points,
  // 10 coordinates, 6 parameters: 4 degrees of freedom), floored at min_pixel_sigma.
  if (!five_point_solver_.solve(camera_, pixels, &solution, reason)) return SolveOutcome::kSolverFailed;
  const double residual_variance = solution.reprojection_rms_px * solution.reprojection_rms_px * kMarkerCount / 4.0;
  const double variance = std::max(residual_variance, params_.min_pixel_sigma * params_.min_pixel_sigma);
  std::string covariance_note;
  five_point_solver_.solveWithCovariance(camera_, pixels, variance, &solution, &covariance, &covariance_note);
  if (solution.reprojection_rms_px > params_.max_reprojection_px) {
    *reason = "5-point reprojection error " + std::to_string(solution.reprojection_rms_px) + " px too large";
    return SolveOutcome::kReprojection;
  }
  PoseWithCovariance pose;
  pose.rotation = solution.rotation;
  pose.translation = solution.translation;
  pose.covariance = covariance;
  if (!checkPose(pose, reason)) return SolveOutcome::kImplausible;
  result->pose = pose;
  result->reprojection_error_px = solution.reprojection_rms_px;
  return SolveOutcome::kPassed;
}
StageOutcome MonoPoseEstimator::measureVisible(const cv::Mat& gray, const cv::Rect& region, double face_width_px,
                                               MonoPoseResult* result) {
  if (posedAtPredictedFace(gray, region, result)) return {};
  FaceMatch match;
  double direct_sigma_px = 0.0;
  const StageOutcome found = findFace(gray, region, face_width_px, &match, &direct_sigma_px, result);
  if (!found.passed()) return found;
  return poseFromMatch(gray, match, direct_sigma_px, result);
}

bool MonoPoseEstimator::posedAtPredictedFace(const cv::Mat& gray, const cv::Rect& region, MonoPoseResult* result) {
  // Tracking (the face's place and perspective are predicted, also from a pose whose orientation was
  // withheld: the refinement keeps only the points the image confirms): refine it there. A prediction that
  // does not hold, or a pose failing a check, falls back to the search from a clean result.
  if (!params_.predict_face_when_tracking || solver_ != PoseSolverType::kPnp || region.area() <= 0) {
    return false;
  }
  const MonoPoseResult before = *result;
  const FaceMatch predicted = matchPredictedFace(gray, result->stamp_s);
  if (!predicted.found) return false;
  result->used_tracking_region = true;
  result->used_predicted_face = true;
  result->search_region = region;
  result->feature_inliers = predicted.inliers;
  result->inlier_points = predicted.inlier_image_points;
  result->face_outline = predicted.face_outline;
  if (poseFromMatch(gray, predicted, 0.0, result).passed()) return true;
  *result = before;
  return false;
}

StageOutcome MonoPoseEstimator::findFace(const cv::Mat& gray, const cv::Rect& region, double face_width_px,
                                         FaceMatch* match, double* direct_sigma_px, MonoPoseResult* result) {
  std::vector<SearchRegion> priors = {{region, face_width_px}};
  const bool hint_fresh = hintFresh(result->stamp_s);
  if (hint_fresh && region.area() <= 0) priors.push_back({hint_region_, 0.0});
  // Features where a prior puts the face (cheap: small regions); without a track, its five dots anywhere (any
  // roll, under blur); then features over the full frame (dots hidden by glare or an occluder); then the
  // direct alignment. (While tracking, the track is the better prior: near contact the dots leave the
  // model pyramid's sizes and the search would only cost.)
  std::string dots_status = "not searched while tracking";
  std::optional<DotsPrior> dots;  // the dots' pose that looked most like the face
  if (!findFaceByFeatures(gray, priors, /*full_frame=*/false, match, result) &&
      (tracking_ || !findFaceByDots(gray, match, &dots_status, &dots, result))) {
    findFaceByFeatures(gray, {}, /*full_frame=*/true, match, result);
    if (!match->found) match->status += "; dots: " + dots_status;
  }
  if (!match->found && params_.use_direct_alignment && (dots || directSearchDue())) {
    alignFaceDirectly(gray, hint_fresh, dots ? &*dots : nullptr, match, direct_sigma_px, result);
  }
  if (!match->found) {
    return refuse(result, outcomeOf(Stage::kFind, FindOutcome::kFaceNotFound), RejectReason::kNotFound, match->status);
  }
  return {};
}

bool MonoPoseEstimator::findFaceByFeatures(const cv::Mat& gray, const std::vector<SearchRegion>& regions,
                                           bool full_frame, FaceMatch* match, MonoPoseResult* result) {
  const FaceSearchOutcome search =
      searchFace(matcher_, gray, regions, params_.use_half_resolution, &preferred_level_, full_frame);
  *match = search.match;
  double spread = 0.0;
  if (match->found && !spansFace(*match, &spread)) {
    match->found = false;
    match->status = "the features' inliers span only " + std::to_string(spread) + " of the face (min_inlier_spread)";
  }
  result->used_tracking_region = match->found && search.prior_index == 0;
  result->used_region_hint = match->found && search.prior_index == 1;
  result->search_region = search.region;
  result->pyramid_level = match->pyramid_level;
  result->feature_matches = match->matches;
  result->feature_inliers = match->inliers;
  result->matched_points = match->matched_image_points;
  result->inlier_points = match->inlier_image_points;
  result->face_outline = match->face_outline;
  return match->found;
}

bool MonoPoseEstimator::findFaceByDots(const cv::Mat& gray, FaceMatch* match, std::string* status,
                                       std::optional<DotsPrior>* best_looking, MonoPoseResult* result) const {
  // Patterns solved per image, best geometry first (each costs a solve and an appearance score). The print's
  // own dark details and the clutter's form patterns too, under blur often with better geometry than the
  // dots': the face's appearance at each pattern's pose decides (the target's ~0.9, others' < 0.4).
  constexpr size_t kMaxDotPatterns = 8;
  struct Solved {
    LedPatternCandidate pattern;
    PoseWithCovariance pose;
    AppearanceScore appearance;
  };
  std::vector<Solved> solved;
  for (const LedPatternCandidate& pattern : dotPatterns(gray, kMaxDotPatterns, status)) {
    PoseWithCovariance pose;
    if (!patternPose(pattern.pixels, &pose, status)) continue;
    solved.push_back({pattern, pose, appearance_.score(gray, camera_, pose)});
  }
  std::stable_sort(solved.begin(), solved.end(), [](const Solved& a, const Solved& b) {
    return a.appearance.median_ncc > b.appearance.median_ncc;
  });
  if (!solved.empty()) {
    const Solved& best = solved.front();
    *best_looking = DotsPrior{best.pose, best.pattern.pixels, best.appearance.blur_sigma_px};
  }
  for (const Solved& candidate : solved) {
    const LedPatternCandidate& pattern = candidate.pattern;
    const PoseWithCovariance& pose = candidate.pose;
    FaceMatch at = matcher_.matchAtPrediction(gray, normalisedFaceHomography(pose), kPredictedFaceMinKeptFraction);
    if (!at.found) {
      *status = "the face at the dots' pose: " + at.status;
      continue;
    }
    if (!faceKeepsDots(at.homography, pattern.pixels, status)) continue;
    *match = at;
    result->found_by_dots = true;
    result->search_region = cv::Rect(0, 0, gray.cols, gray.rows);
    // The model points correlated where the dots' pose put them play the feature matches' part.
    result->feature_matches = std::max(match->refine_candidates, match->inliers);
    result->feature_inliers = match->inliers;
    result->inlier_points = match->inlier_image_points;
    result->face_outline = match->face_outline;
    return true;
  }
  return false;
}

bool MonoPoseEstimator::patternPose(const MarkerPixels& pixels, PoseWithCovariance* pose, std::string* reason) const {
  // The closed form identifies (its depths and arms must agree with the model); the least-squares pose it
  // starts judges: the closed form's own residual grows with small centre errors (4-7 px from dots within
  // 1 px of the truth, blurred at 1.7 m), the pattern's fit does not. For the dots and the LEDs alike.
  FivePointSolution closed_form;
  if (!five_point_solver_.solve(camera_, pixels, &closed_form, reason)) return false;
  const std::vector<Eigen::Vector3d> model(model_.markers().begin(), model_.markers().end());
  const std::vector<Eigen::Vector2d> image(pixels.begin(), pixels.end());
  PlanarPnpSolution solution;
  if (!pnp_solver_.solve(camera_, model, image, &closed_form.rotation, &solution, reason)) return false;
  if (solution.reprojection_rms_px > params_.max_reprojection_px) {
    *reason = "5-point reprojection error " + std::to_string(solution.reprojection_rms_px) + " px too large";
    return false;
  }
  if (!checkPose(solution.pose, reason)) return false;
  *pose = solution.pose;
  return true;
}

bool MonoPoseEstimator::faceKeepsDots(const cv::Matx33d& face, const MarkerPixels& dots, std::string* reason) const {
  // Two measures of one face: the refined texture must put each dot within that dot's radius of where it
  // was found (a refinement that slid along a blurred texture moves the face, not the dots).
  for (int i = 0; i < kMarkerCount; ++i) {
    double radius_px = 0.0;
    const Eigen::Vector2d at = predictedDot(face, i, &radius_px);
    const double moved = (at - dots[static_cast<size_t>(i)]).norm();
    if (moved > std::max(radius_px, 1.0)) {
      *reason = "the face refined at the dots' pose moves dot " + std::to_string(i) + " by " + std::to_string(moved) +
                " px (radius " + std::to_string(radius_px) + ")";
      return false;
    }
  }
  return true;
}

std::vector<LedPatternCandidate> MonoPoseEstimator::dotPatterns(const cv::Mat& gray, size_t max_patterns,
                                                               std::string* reason) const {
  // Dots per radius: the target's five among the print's other dark details and the clutter's.
  constexpr size_t kMaxDotsPerRadius = 16;
  // The longer arm (marker 0 to 2) is this many dot radii on the face; seen turned, in perspective and at the
  // neighbouring radius, between these fractions of it.
  const double arm_in_radii = (model_.markers()[0] - model_.markers()[2]).norm() / model_.markerRadius();
  constexpr double kMinArmFraction = 0.4;
  constexpr double kMaxArmFraction = 1.6;
  const std::vector<std::vector<LedBlob>> by_radius = dot_finder_.find(gray, kMaxDotsPerRadius);
  std::vector<LedPatternCandidate> patterns;
  for (size_t i = 0; i < by_radius.size(); ++i) {
    const double radius = dot_finder_.radii()[i];
    for (const LedPatternCandidate& pattern : led_detector_.identifyPattern(by_radius[i], reason)) {
      const double arm = (pattern.pixels[0] - pattern.pixels[2]).norm() / (arm_in_radii * radius);
      if (arm >= kMinArmFraction && arm <= kMaxArmFraction) patterns.push_back(pattern);
    }
  }
  if (patterns.empty()) *reason = "no 5-dot pattern of one dot size";
  std::sort(patterns.begin(), patterns.end(),
            [](const LedPatternCandidate& a, const LedPatternCandidate& b) { return a.score < b.score; });
  if (patterns.size() > max_patterns) patterns.resize(max_patterns);
  return patterns;
}

void MonoPoseEstimator::alignFaceDirectly(const cv::Mat& gray, bool hint_fresh, const DotsPrior* dots,
                                          FaceMatch* match, double* direct_sigma_px, MonoPoseResult* result) {
  // The prior: the track; else the dots' pose; else (the dots may be another object's dark spots) the hint.
  DirectAlignment direct;
  bool from_dots = false;
  if (dots != nullptr) {  // only searched without a track
    // The dots' pose is exact enough to measure the image's blur there (the appearance score's best
    // template blur): the face is aligned blurred alike.
    direct = direct_aligner_.align(gray, normalisedFaceHomography(dots->pose), /*coarse_only=*/false, dots->blur_px);
    std::string moved;
    if (direct.found && !faceKeepsDots(direct.homography, dots->dots, &moved)) {
      direct.found = false;
      direct.status = moved;
    }
    from_dots = direct.found;
    if (!from_dots) match->status += "; direct alignment at the dots' pose: " + direct.status;
  }
  const bool from_hint = !tracking_ && !from_dots && hint_fresh;
  if (!from_dots) {
    direct = alignDirect(gray, tracking_, hint_fresh, result->stamp_s);
    noteDirectSearch(from_hint, direct.found);
  }
  result->direct_correlation = direct.correlation;
  if (!direct.found) {
    if (!direct.status.empty()) match->status += "; direct alignment: " + direct.status;
    return;
  }
  match->found = true;
  match->homography = direct.homography;
  match->inlier_texture_points = direct.texture_points;
  match->inlier_image_points = direct.image_points;
  match->face_outline = direct.face_outline;
  match->inliers = static_cast<int>(direct.image_points.size());
  result->used_direct_alignment = true;
  result->used_tracking_region = tracking_;
  result->used_region_hint = from_hint;
  result->found_by_dots = from_dots;
  result->inlier_points = direct.image_points;
  result->face_outline = direct.face_outline;
  *direct_sigma_px = direct.pixel_sigma_px;
}
// The search from a hint tries every yaw hypothesis (~25-35 ms on a blurred 2 m face) and, where the face
// cannot be found (glare), would do so on every frame: after each failure it waits 1, 2, then 3 frames
// (kMaxDirectBackoffFrames) before the next try, so a blind stretch costs ~a quarter of that on average.
bool MonoPoseEstimator::directSearchDue() {
  if (tracking_ || direct_backoff_left_ <= 0) return true;
  --direct_backoff_left_;
  return false;
}

void MonoPoseEstimator::noteDirectSearch(bool from_hint, bool found) {
  if (!from_hint || found) {
    direct_failures_ = 0;
    direct_backoff_left_ = 0;
    return;
  }
  constexpr int kMaxDirectBackoffFrames = 3;
  direct_failures_ = std::min(direct_failures_ + 1, kMaxDirectBackoffFrames);
  direct_backoff_left_ = direct_failures_;
}

Eigen::Vector3d MonoPoseEstimator::hintPosition() const {
  if (hint_has_position_) return hint_position_;
  // A region hint is a detector's box around the face, grown by about a third: the face's height (which
  // yaw does not shorten) is about this fraction of the box's.
  constexpr double kRegionHintFaceFraction = 0.77;
  const Eigen::Vector2d centre(hint_region_.x + 0.5 * hint_region_.width, hint_region_.y + 0.5 * hint_region_.height);
  const double range_z = camera_.fy * model_.faceHeight() / (kRegionHintFaceFraction * hint_region_.height);
  return camera_.ray(centre) * range_z;
}

DirectAlignment MonoPoseEstimator::alignDirect(const cv::Mat& gray, bool tracking_prior, bool hint_fresh,
                                              double stamp_s) const {
  if (tracking_prior) {
    PoseWithCovariance predicted = last_pose_;
    if (stamp_s > last_stamp_s_ && stamp_s - last_stamp_s_ <= params_.filter.max_gap_s) filter_.predict(stamp_s, &predicted);
    return direct_aligner_.align(gray, camera_, predicted);
  }
  DirectAlignment best;
  if (!hint_fresh) {
    best.status = "no prior (tracking, dots or hint)";
    return best;
  }
  // The hint gives a position only: the face looking along the optical axis (the upright texture), turned
  // by each yaw about its vertical axis; the coarse levels score the hypotheses, the best is refined.
  PoseWithCovariance hypothesis;
  hypothesis.translation = hintPosition();
  Eigen::Matrix3d facing;
  facing.col(0) = Eigen::Vector3d(0, 0, -1);  // face normal (target x) towards the camera
  facing.col(1) = Eigen::Vector3d(1, 0, 0);   // target y (viewer's right) -> image right
  facing.col(2) = Eigen::Vector3d(0, -1, 0);  // target z (up) -> image up
  // 5 yaws, 15 deg apart over the shipped +-30 deg (the coarse levels score each).
  constexpr int count = 5;
  for (int i = 0; i < count; ++i) {
    const double yaw_deg = params_.direct_max_yaw_deg * (2.0 * i / (count - 1) - 1.0);
    hypothesis.rotation = facing * Eigen::AngleAxisd(yaw_deg * M_PI / 180.0, Eigen::Vector3d::UnitZ()).toRotationMatrix();
    const DirectAlignment coarse =
        direct_aligner_.align(gray, faceHomography(model_, camera_, hypothesis), /*coarse_only=*/true);
    if (coarse.correlation > best.correlation) best = coarse;
  }
  if (best.face_outline.empty()) return best;  // no hypothesis converged
  return direct_aligner_.align(gray, best.homography);
}

StageOutcome MonoPoseEstimator::poseFromMatch(const cv::Mat& gray, const FaceMatch& match, double direct_sigma_px,
                                              MonoPoseResult* result) {
  return solver_ == PoseSolverType::kPnp ? pnpPoseFromMatch(gray, match, direct_sigma_px, result)
                                         : fivePointPoseFromMatch(gray, match, result);
}

StageOutcome MonoPoseEstimator::pnpPoseFromMatch(const cv::Mat& gray, const FaceMatch& match, double direct_sigma_px,
                                                 MonoPoseResult* result) {
  std::string reason;
  std::vector<Eigen::Vector3d> model_points;
  std::vector<Eigen::Vector2d> image_points;
  correspondences(match, &model_points, &image_points);
  Eigen::Matrix3d previous_storage;
  PlanarPnpSolution solution;
  if (!pnp_solver_.solve(camera_, model_points, image_points, previousRotation(result->stamp_s, &previous_storage),
                         &solution, &reason)) {
    return refuse(result, outcomeOf(Stage::kSolve, SolveOutcome::kSolverFailed), RejectReason::kSolverFailed, reason);
  }
  result->pnp_ambiguous = solution.ambiguous;
  result->pose_points = static_cast<int>(model_points.size());
  result->reprojection_error_px = solution.reprojection_rms_px;
  if (solution.reprojection_rms_px > params_.max_reprojection_px) {
    return refuse(result, outcomeOf(Stage::kSolve, SolveOutcome::kReprojection), RejectReason::kReprojection,
                  "PnP reprojection error " + std::to_string(solution.reprojection_rms_px) + " px too large");
  }
  if (!checkPose(solution.pose, &reason)) {
    return refuse(result, outcomeOf(Stage::kSolve, SolveOutcome::kImplausible), RejectReason::kImplausiblePose, reason);
  }
  result->pose = solution.pose;
  const double pixel_sigma = result->used_direct_alignment ? direct_sigma_px : solution.reprojection_rms_px;
  return vetVisiblePose(gray, match, model_points, &solution, pixel_sigma, result);
}

void MonoPoseEstimator::correspondences(const FaceMatch& match, std::vector<Eigen::Vector3d>* model_points,
                                        std::vector<Eigen::Vector2d>* image_points) const {
  model_points->reserve(match.inlier_texture_points.size());
  for (size_t i = 0; i < match.inlier_texture_points.size(); ++i) {
    model_points->push_back(model_.texturePixelToPoint(match.inlier_texture_points[i]));
    image_points->emplace_back(match.inlier_image_points[i].x, match.inlier_image_points[i].y);
  }
}

StageOutcome MonoPoseEstimator::fivePointPoseFromMatch(const cv::Mat& gray, const FaceMatch& match,
                                                       MonoPoseResult* result) {
  // paper_5point: the printed dots, where the homography says they are.
  MarkerPixels pixels;
  MarkerPixels predicted;
  double dot_radius_px = 0.0;
  std::string reason;
  for (int i = 0; i < kMarkerCount; ++i) {
    double radius_px = 0.0;
    predicted[static_cast<size_t>(i)] = predictedDot(match.homography, i, &radius_px);
    dot_radius_px = std::max(dot_radius_px, radius_px);
    if (!dot_locator_.locate(gray, predicted[static_cast<size_t>(i)], radius_px, &pixels[static_cast<size_t>(i)], &reason)) {
      return refuse(result, outcomeOf(Stage::kSolve, SolveOutcome::kDotNotLocated), RejectReason::kDotAppearance,
                    "marker " + std::to_string(i) + ": " + reason);
    }
  }
  result->marker_pixels.assign(pixels.begin(), pixels.end());
  result->pose_points = kMarkerCount;
  const SolveOutcome solved = solveFivePoint(pixels, result, &reason);
  if (solved != SolveOutcome::kPassed) {
    return refuse(result, outcomeOf(Stage::kSolve, solved), rejectReasonOf(solved), reason);
  }
  std::vector<Eigen::Vector3d> model_points;
  std::vector<Eigen::Vector2d> image_points;
  correspondences(match, &model_points, &image_points);
  const StageOutcome vetted = vetFivePointPose(predicted, pixels, dot_radius_px, model_points, image_points, result);
  if (!vetted.passed()) return vetted;
  const std::vector<Eigen::Vector3d> markers(model_.markers().begin(), model_.markers().end());
  return vetVisiblePose(gray, match, markers, nullptr, result->reprojection_error_px, result);
}

Eigen::Vector2d MonoPoseEstimator::predictedDot(const cv::Matx33d& homography, int marker_index, double* radius_px) const {
  const Eigen::Vector3d& marker = model_.markers()[static_cast<size_t>(marker_index)];
  const cv::Point2d texture_pixel = model_.pointToTexturePixel(marker);
  const Eigen::Vector2d centre = applyHomography(homography, {texture_pixel.x, texture_pixel.y});
  const cv::Point2d texture_edge = model_.pointToTexturePixel(marker + Eigen::Vector3d(0.0, model_.markerRadius(), 0.0));
  const cv::Point2d texture_edge_z = model_.pointToTexturePixel(marker + Eigen::Vector3d(0.0, 0.0, model_.markerRadius()));
  *radius_px = std::max((applyHomography(homography, {texture_edge.x, texture_edge.y}) - centre).norm(),
                        (applyHomography(homography, {texture_edge_z.x, texture_edge_z.y}) - centre).norm());
  return centre;
}
StageOutcome MonoPoseEstimator::measureIr(const cv::Mat& gray, const cv::Rect& region, MonoPoseResult* result) {
  LedSearch search;
  if (region.area() > 0) {
    result->search_region = region;
    if (poseFromLeds(gray, region, &search, result)) {
      result->used_tracking_region = true;
      return {};
    }
  }
  result->search_region = cv::Rect(0, 0, gray.cols, gray.rows);
  if (poseFromLeds(gray, cv::Rect(), &search, result)) return {};
  const std::string status = search.reason.empty() ? "LED pattern not found" : search.reason;
  if (search.blob_rejected) {
    return refuse(result, outcomeOf(Stage::kFind, FindOutcome::kLedBlobShape), RejectReason::kLedBlobShape, status);
  }
  // A pattern whose pose failed is still "not found" for the coarse code: no LED pattern gave a pose.
  const StageOutcome outcome = search.candidate_unsolved ? outcomeOf(Stage::kSolve, SolveOutcome::kSolverFailed)
                                                         : outcomeOf(Stage::kFind, FindOutcome::kNoLedPattern);
  return refuse(result, outcome, RejectReason::kNotFound, status);
}

bool MonoPoseEstimator::poseFromLeds(const cv::Mat& gray, const cv::Rect& roi, LedSearch* search,
                                     MonoPoseResult* result) const {
  const std::vector<LedBlob> blobs = led_detector_.detectBlobs(gray, roi);
  result->feature_matches = static_cast<int>(blobs.size());
  result->blob_pixels.clear();
  for (const LedBlob& blob : blobs) result->blob_pixels.push_back(blob.centroid);
  const std::vector<LedPatternCandidate> candidates = led_detector_.identifyPattern(blobs, &search->reason);
  // Patterns tried per image, best first: the rest are made of reflections, and each costs a solve.
  constexpr int kMaxPatternCandidates = 6;
  const int tries = std::min(static_cast<int>(candidates.size()), kMaxPatternCandidates);
  for (int c = 0; c < tries; ++c) {
    const LedPatternCandidate& candidate = candidates[static_cast<size_t>(c)];
    if (!vetLedBlobs(blobs, candidate, &search->reason)) {
      search->blob_rejected = true;
      continue;
    }
    // The 5-point solve also validates the identification (scale consistency, face orientation); with pnp
    // the least-squares pose it starts judges the pattern (patternPose), paper_5point publishes the closed form's.
    MonoPoseResult trial = *result;
    search->candidate_unsolved = true;
    const bool solved = solver_ == PoseSolverType::kPnp
                            ? patternPose(candidate.pixels, &trial.pose, &search->reason)
                            : solveFivePoint(candidate.pixels, &trial, &search->reason) == SolveOutcome::kPassed;
    if (!solved) continue;
    if (!refineIrPose(candidate.pixels, medianStreakSigma(blobs, candidate), &trial, &search->reason)) continue;
    *result = trial;
    result->feature_inliers = kMarkerCount;
    result->pose_points = kMarkerCount;
    result->marker_pixels.assign(candidate.pixels.begin(), candidate.pixels.end());
    return true;
  }
  return false;
}
bool MonoPoseEstimator::refineIrPose(const MarkerPixels& pixels, double median_streak_px, MonoPoseResult* trial,
                                     std::string* reason) const {
  // Motion smears each LED into a streak whose centroid the blur moves by a fraction of a pixel that the
  // residual of five points cannot show: the covariance grows with the streaks beyond a still spot's.
  const double still = kStillLedStreakPx;
  trial->blur_sigma_px = std::sqrt(std::max(0.0, median_streak_px * median_streak_px - still * still));
  if (solver_ != PoseSolverType::kPnp) {
    const double blur_factor = 1.0 + params_.consistency.covariance_blur_gain * trial->blur_sigma_px;
    trial->pose.covariance *= blur_factor * blur_factor;
    return true;
  }
  const std::vector<Eigen::Vector3d> model(model_.markers().begin(), model_.markers().end());
  const std::vector<Eigen::Vector2d> image(pixels.begin(), pixels.end());
  Eigen::Matrix3d previous_storage;
  const Eigen::Matrix3d* claimed_previous = previousRotation(trial->stamp_s, &previous_storage);
  // No claimed history: the 5-point pose picks the IPPE branch, but from the same five points, so its
  // pick is no evidence: an alternative that fits as well stays in the covariance (below).
  const Eigen::Matrix3d* previous = claimed_previous != nullptr ? claimed_previous : &trial->pose.rotation;
  PlanarPnpSolution solution;
  if (!pnp_solver_.solve(camera_, model, image, previous, &solution, reason)) return false;
  if (solution.reprojection_rms_px > params_.max_reprojection_px || !checkPose(solution.pose, reason)) return false;
  trial->pose = solution.pose;
  trial->reprojection_error_px = solution.reprojection_rms_px;
  trial->pnp_ambiguous = solution.ambiguous;
  OrientationHistory history;
  history.claimed = claimed_previous;
  trial->ambiguity_deg = modelPnpCovariance(camera_, solution, history, model, solution.reprojection_rms_px,
                                             solution.reprojection_rms_px, params_.min_pixel_sigma,
                                             trial->blur_sigma_px, params_.consistency, &trial->pose);
  return true;
}

OrientationOutcome MonoPoseEstimator::claimOrientation(MonoPoseResult* result) {
  // A valid pose: nothing refused it (a stage before may have, and the inner pattern answered instead).
  result->status.clear();
  result->reject_reason = RejectReason::kNone;
  result->stage = Stage::kNone;
  result->stage_outcome = 0;
  scaleByInnovation(result);
  const OrientationOutcome outcome = orientationOutcome(result);
  result->orientation_valid = outcome == OrientationOutcome::kClaimed;
  return outcome;
}

OrientationOutcome MonoPoseEstimator::orientationOutcome(MonoPoseResult* result) const {
  if (result->ambiguity_deg > params_.consistency.max_ambiguity_deg) {
    result->status = "orientation withheld: IPPE's two poses fit alike and differ by " +
                     std::to_string(result->ambiguity_deg) + " deg (max_ambiguity_deg)";
    return OrientationOutcome::kAmbiguous;
  }
  if (params_.consistency.confirm_new_orientation && !result->rotation_innovation_checked) {
    result->status = "orientation withheld: a first pose, nothing to confirm it yet (confirm_new_orientation)";
    return OrientationOutcome::kUnconfirmed;
  }
  return orientationClaimed(result->pose, params_.consistency, &result->status) ? OrientationOutcome::kClaimed
                                                                                 : OrientationOutcome::kUncertain;
}
void MonoPoseEstimator::scaleByInnovation(MonoPoseResult* result) {
  // The running mean survives a lost frame or a filter restart: blur that broke tracking is still there.
  PoseWithCovariance predicted;
  if (filter_.initialized() && result->stamp_s > filter_.lastStamp() &&
      result->stamp_s - filter_.lastStamp() <= params_.filter.max_gap_s && filter_.predict(result->stamp_s, &predicted)) {
    innovation_scale_.update(result->pose, predicted);
    result->rotation_innovation_checked = true;
  }
  innovation_scale_.apply(&result->pose.covariance);
  result->covariance_scale_position = innovation_scale_.positionScale();
  result->covariance_scale_rotation = innovation_scale_.rotationScale();
}

bool MonoPoseEstimator::updateVelocities(MonoPoseResult* result) {
  std::string filter_note;
  std::string difference_note;
  const bool filter_ok = filter_.update(result->stamp_s, result->pose, &filter_note);
  frame_difference_.update(result->stamp_s, result->pose, &difference_note);
  result->twist_filter = filter_.twist();
  result->twist_frame_difference = frame_difference_.twist();
  if (!filter_ok) result->twist_filter.valid = false;  // this pose was not fused: no fresh velocity
  if (velocity_ == VelocityMethod::kFilter) {
    result->twist = result->twist_filter;
    result->velocity_status = filter_note;
  } else {
    result->twist = result->twist_frame_difference;
    result->velocity_status = difference_note;
  }
  if (!result->twist.valid && result->velocity_status.empty()) {
    result->velocity_status = "velocity needs two poses within filter.max_gap_s";
  }
  return filter_ok;
}

void MonoPoseEstimator::publishFilteredOrientation(bool fused, MonoPoseResult* result) const {
  result->measured_pose = result->pose;
  // One fused pose is the measurement itself; a gated one left the filter at its prediction.
  constexpr int kMinFusedPoses = 2;
  if (!params_.publish_filtered_orientation || !fused || filter_.updatesSinceRestart() < kMinFusedPoses) return;
  // The filter averages what it takes for independent errors; the part of an image's error that persists
  // from image to image (a tilt bias that moves with the blur) does not average out, so it stays in. The
  // position keeps its own block; its correlation with the (now filtered) rotation is not known: dropped.
  const double persistent = kPersistentOrientationFraction;
  const PoseWithCovariance posterior = filter_.pose();
  const Matrix6d& measured = result->measured_pose.covariance;
  result->pose.rotation = posterior.rotation;
  result->pose.covariance.setZero();
  result->pose.covariance.topLeftCorner<3, 3>() = measured.topLeftCorner<3, 3>();
  result->pose.covariance.bottomRightCorner<3, 3>() =
      posterior.covariance.bottomRightCorner<3, 3>() + persistent * persistent * measured.bottomRightCorner<3, 3>();
  result->orientation_filtered = true;
}

// ---- The inner pattern (target.yaml `inner_pattern`): close range, to contact. ----------------------
cv::Rect MonoPoseEstimator::predictedInnerPatternRegion(double stamp_s) const {
  if (!params_.use_tracking_region || !tracking_) return cv::Rect();
  PoseWithCovariance predicted = last_pose_;
  if (stamp_s > last_stamp_s_ && stamp_s - last_stamp_s_ <= params_.filter.max_gap_s) {
    filter_.predict(stamp_s, &predicted);
  }
  const TagSpec& tag = model_.innerPattern();
  const Eigen::Isometry3d target_T_tag = targetTTag(tag);
  const double half_print = 0.5 * tag.size_m * 10.0 / 8.0;  // the white ring included
  double min_x = 1e9, min_y = 1e9, max_x = -1e9, max_y = -1e9;
  for (const double sx : {-1.0, 1.0}) {
    for (const double sy : {-1.0, 1.0}) {
      const Eigen::Vector3d p = predicted.rotation * (target_T_tag * Eigen::Vector3d(sx * half_print, sy * half_print, 0.0)) +
                                predicted.translation;
      if (p.z() < 0.02) return cv::Rect();
      const Eigen::Vector2d pixel = camera_.project(p);
      min_x = std::min(min_x, pixel.x());
      min_y = std::min(min_y, pixel.y());
      max_x = std::max(max_x, pixel.x());
      max_y = std::max(max_y, pixel.y());
    }
  }
  // Half the print's size again around it, plus the face's tracking margin: the motion between images.
  const double margin = 0.5 * std::max(max_x - min_x, max_y - min_y) + params_.tracking_margin_px;
  const cv::Rect region(cv::Point(static_cast<int>(std::floor(min_x - margin)), static_cast<int>(std::floor(min_y - margin))),
                        cv::Point(static_cast<int>(std::ceil(max_x + margin)), static_cast<int>(std::ceil(max_y + margin))));
  return region & cv::Rect(0, 0, camera_.width, camera_.height);
}

InnerPatternOutcome MonoPoseEstimator::applyInnerPattern(const cv::Mat& gray, MonoPoseResult* result) {
  if (!inner_pattern_ || !params_.inner_pattern.enabled || mode_ != MonoMode::kVisible) return {};
  // The face's pose (hundreds of points) stands where there is one: the tag is for where the face fails.
  // (A cross-check of the two, refusing the image when they disagreed, changed no estimate of the held-out
  // replay: removed, and with it the tag's search on images the face gave a pose.)
  if (result->valid) return {};
  // Only near the target (the last pose, from any solver): the tag is too small to help farther, and the
  // search costs CPU.
  if (!(last_valid_range_m_ < params_.inner_pattern.use_range_m)) return {};
  double tag_ambiguity_deg = 0.0;
  InnerPatternResult tag = findInnerTag(gray, &tag_ambiguity_deg, result);
  if (!tag.valid) return {};  // the face's result stands
  result->valid = true;
  result->status.clear();
  result->solver = kInnerPatternSolverName;
  result->pose = tag.pose;
  result->pose_points = tag.pose_points;
  result->feature_matches = tag.candidate_points;  // the arbiter's evidence: grid corners found ...
  result->feature_inliers = tag.pose_points;       // ... and used by the pose
  result->reprojection_error_px = tag.reprojection_rms_px;
  result->pnp_ambiguous = tag.pnp.ambiguous;
  result->ambiguity_deg = tag_ambiguity_deg;
  return {};
}

InnerPatternResult MonoPoseEstimator::findInnerTag(const cv::Mat& gray, double* ambiguity_deg,
                                                   MonoPoseResult* result) const {
  Eigen::Matrix3d previous_storage;
  const Eigen::Matrix3d* previous = previousRotation(result->stamp_s, &previous_storage);
  // Where the tracked pose puts the print, then (if not found there) the whole image: the region
  // saves most of apriltag's CPU time near contact.
  const cv::Rect region = predictedInnerPatternRegion(result->stamp_s);
  InnerPatternResult tag = inner_pattern_->detect(gray, camera_, previous, region);
  if (!tag.valid && region.area() > 0) tag = inner_pattern_->detect(gray, camera_, previous);
  result->inner_pattern_status = tag.valid ? "" : tag.status;
  if (!tag.valid) return tag;
  // The tag's pose takes the covariance model of every PnP pose. Its fit's covariance alone claimed
  // ~3 deg at 0.3-0.45 m when IPPE's other solution, 10-13 deg away, fitted as well and no claimed
  // orientation decided: one of those was the pose, and it was 11 deg off. The tag's own poses often
  // claim no orientation there (sigma above max_rotation_sigma_deg), so the tracked orientation, claimed
  // or not, weighs in by its covariance: it keeps a smooth approach decided.
  OrientationHistory history;
  history.claimed = previous;
  PoseWithCovariance tracked;
  if (trackedPose(result->stamp_s, &tracked)) history.tracked = &tracked;
  *ambiguity_deg =
      modelPnpCovariance(camera_, tag.pnp, history, tag.model_points, tag.reprojection_rms_px, tag.reprojection_rms_px,
                         InnerPatternDetector::kMinPixelSigmaPx, 0.0, params_.consistency, &tag.pose);
  return tag;
}
void MonoPoseEstimator::updateFaceRetry(bool face_skipped, const MonoPoseResult& result) {
  if (!result.valid) {
    face_searches_skipped_left_ = 0;  // nothing to stand on: the next image searches the face again
  } else if (!face_skipped && result.solver == kInnerPatternSolverName) {
    face_searches_skipped_left_ = kFaceRetryEvery - 1;  // the face failed, the tag did not
  }
}

// The pipeline (stages.h; README "mono_pose", "Stages"): each stage's outcome is recorded in the result, the
// one that decides goes on the wire.
MonoPoseResult MonoPoseEstimator::process(const cv::Mat& image, double stamp_s) {
  const double start_ms = threadCpuTimeMs();
  MonoPoseResult result;
  result.stamp_s = stamp_s;
  result.solver = params_.solver;
  cv::Mat gray;
  if (record(&result, Stage::kInput, readImage(image, &gray, &result))) {
    const bool skip_face = face_searches_skipped_left_ > 0;
    if (skip_face) {
      record(&result, Stage::kFind, skipFaceSearch(&result));
    } else {
      record(&result, measurePose(gray, &result));  // find, solve, vet
    }
    record(&result, Stage::kInnerPattern, applyInnerPattern(gray, &result));
    updateFaceRetry(skip_face, result);
    record(&result, Stage::kHint, checkPositionHint(&result));
  }
  if (result.valid) {
    record(&result, Stage::kOrientation, claimOrientation(&result));
    trackPose(&result);
    record(&result, Stage::kPosition, claimPosition(&result));
    if (result.stage == Stage::kNone) result.stage = kLastStage;  // every stage passed
  } else {
    tracking_ = false;
    result.velocity_status = "no pose";
  }
  result.processing_time_ms = threadCpuTimeMs() - start_ms;
  return result;
}

InputOutcome MonoPoseEstimator::readImage(const cv::Mat& image, cv::Mat* gray, MonoPoseResult* result) const {
  InputOutcome outcome = InputOutcome::kPassed;
  if (image.empty()) {
    result->status = "empty image";
    outcome = InputOutcome::kEmpty;
  } else if (image.cols != camera_.width || image.rows != camera_.height) {
    result->status = "image is " + std::to_string(image.cols) + "x" + std::to_string(image.rows) +
                     ", camera_info says " + std::to_string(camera_.width) + "x" + std::to_string(camera_.height);
    outcome = InputOutcome::kWrongSize;
  } else if (image.type() == CV_8UC1) {
    *gray = image;
  } else if (image.type() == CV_8UC3) {
    cv::cvtColor(image, *gray, cv::COLOR_BGR2GRAY);
  } else {
    result->status = "unsupported image type (need 8-bit gray or BGR)";
    outcome = InputOutcome::kWrongType;
  }
  if (outcome != InputOutcome::kPassed) result->reject_reason = RejectReason::kBadInput;
  return outcome;
}

FindOutcome MonoPoseEstimator::skipFaceSearch(MonoPoseResult* result) {
  --face_searches_skipped_left_;
  result->face_search_skipped = true;
  result->status = "face search skipped: near contact the inner pattern gives the pose";
  result->reject_reason = RejectReason::kNotFound;
  return FindOutcome::kFaceSearchSkipped;
}

StageOutcome MonoPoseEstimator::measurePose(const cv::Mat& gray, MonoPoseResult* result) {
  double face_width_px = 0.0;
  const cv::Rect region = predictedRegion(result->stamp_s, &face_width_px);
  const StageOutcome outcome = mode_ == MonoMode::kVisible ? measureVisible(gray, region, face_width_px, result)
                                                           : measureIr(gray, region, result);
  result->valid = outcome.passed();
  return outcome;
}

void MonoPoseEstimator::trackPose(MonoPoseResult* result) {
  result->range_m = result->pose.translation.norm();
  const bool fused = updateVelocities(result);
  tracking_ = true;
  last_orientation_claimed_ = result->orientation_valid;
  last_valid_range_m_ = result->range_m;
  last_pose_ = result->pose;
  last_stamp_s_ = result->stamp_s;
  publishFilteredOrientation(fused, result);
}
PositionOutcome MonoPoseEstimator::claimPosition(MonoPoseResult* result) const {
  // After the tracking state took the pose: it is a measurement with an honest, wide covariance, and the
  // filter, the search region and the covariance's innovation scale go on learning from it (were they
  // not fed, the scale that widened the sigma could never shrink again). Only the claim is withheld.
  std::string note;
  if (positionClaimed(result->pose, params_.consistency, &note)) return PositionOutcome::kClaimed;
  result->valid = false;
  result->orientation_valid = false;
  result->reject_reason = RejectReason::kPositionUncertain;
  result->status = note;
  return PositionOutcome::kUncertain;
}
bool MonoPoseEstimator::hintFresh(double stamp_s) const {
  return hint_region_.area() > 0 && std::abs(stamp_s - hint_stamp_s_) <= params_.region_hint_max_age_s;
}

HintOutcome MonoPoseEstimator::checkPositionHint(MonoPoseResult* result) {
  if (!result->valid) return HintOutcome::kPassed;
  const HintOutcome outcome = hintOutcome(result);
  result->valid = outcome == HintOutcome::kPassed;
  return outcome;
}

HintOutcome MonoPoseEstimator::hintOutcome(MonoPoseResult* result) {
  const ConsistencyParams& c = params_.consistency;
  const double limit = c.max_hint_disagreement_fraction;
  if (limit <= 0.0) return HintOutcome::kPassed;
  const double range = result->pose.translation.norm();
  const double since_s = result->stamp_s - last_hint_disagreement_s_;
  const bool holding = since_s >= 0.0 && since_s <= kHintDisagreementHoldS;
  if (!hint_has_position_ || !hintFresh(result->stamp_s)) {
    if (range < c.hint_check_min_range_m || !holding) return HintOutcome::kPassed;
    result->reject_reason = RejectReason::kHintDisagreement;
    result->status = "no fresh disparity estimate to check the position against, and one " + std::to_string(since_s) +
                     " s ago disagreed (held " + std::to_string(kHintDisagreementHoldS) + " s)";
    return HintOutcome::kHeldWithoutHint;
  }
  const double hint_range = hint_position_.norm();
  if (hint_range < c.hint_check_min_range_m) return HintOutcome::kPassed;
  // Ranges, not positions: the check is for the face's scale bias, which lies along the line of sight,
  // and the hint is up to region_hint_max_age_s old. A turning chaser moves the target's bearing, not
  // its range: at 27 deg/s and 2 m a hint two frames old is 0.06 m to the side of a pose 0.2 % off the
  // truth (eval_real_motion9px_2m refused 43 such poses when positions were compared).
  const double apart = std::abs(range - hint_range);
  // Hysteresis: a pose shown biased must come closer than the first refusal's limit to be trusted again.
  const double fraction = holding ? kHintRecoveryShareOfLimit * limit : limit;
  if (apart <= fraction * range) {
    last_hint_disagreement_s_ = kNoHintDisagreement;
    return HintOutcome::kPassed;
  }
  last_hint_disagreement_s_ = result->stamp_s;
  result->reject_reason = RejectReason::kHintDisagreement;
  result->status = "range " + std::to_string(range) + " m differs from the disparity estimate's " +
                   std::to_string(hint_range) + " m by more than " +
                   (holding ? "half of max_hint_disagreement_fraction (recovering)" : "max_hint_disagreement_fraction") + " of it";
  return holding ? HintOutcome::kNotRecovered : HintOutcome::kRangeDisagrees;
}

bool MonoPoseEstimator::spansFace(const FaceMatch& match, double* spread) const {
  *spread = inlierSpread(match.inlier_texture_points, model_.textureGray().size());
  return *spread >= params_.consistency.min_inlier_spread;
}

StageOutcome MonoPoseEstimator::vetVisiblePose(const cv::Mat& gray, const FaceMatch& match,
                                       const std::vector<Eigen::Vector3d>& model_points, const PlanarPnpSolution* pnp,
                                               double pixel_sigma_px, MonoPoseResult* result) const {
  const ConsistencyParams& c = params_.consistency;
  if (!spansFace(match, &result->inlier_spread)) {
    return refuse(result, outcomeOf(Stage::kVet, VetOutcome::kInlierSpread), RejectReason::kInlierSpread,
                  "pose points cover only " + std::to_string(result->inlier_spread) + " of the face (min_inlier_spread)");
  }
  const AppearanceScore appearance = appearance_.score(gray, camera_, result->pose);
  result->appearance_ncc = appearance.median_ncc;
  result->blur_sigma_px = appearance.blur_sigma_px;
  if (c.min_appearance_ncc >= 0.0 && appearance.median_ncc < c.min_appearance_ncc) {
    return refuse(result, outcomeOf(Stage::kVet, VetOutcome::kAppearance), RejectReason::kAppearance,
                  "the face does not look like the model at this pose (NCC " + std::to_string(appearance.median_ncc) +
                      ", min_appearance_ncc)");
  }
  if (pnp != nullptr) {
    // IPPE's flag compares raw RMS values; with a hundred refined points an alternative at 0.4 px against
    // 0.1 px is clearly worse. A previous orientation decides only when it was claimed. Both solutions
    // share nearly one position: beyond max_ambiguity_deg the orientation is withheld (process()), the
    // position stays; the covariance covers both solutions either way.
    Eigen::Matrix3d previous_storage;
    OrientationHistory history;
    history.claimed = previousRotation(result->stamp_s, &previous_storage);
    result->ambiguity_deg =
        modelPnpCovariance(camera_, *pnp, history, model_points, result->reprojection_error_px, pixel_sigma_px,
                           params_.min_pixel_sigma, appearance.blur_sigma_px, c, &result->pose);
  } else {
    // The 5-point covariance (its own Jacobian) scaled for blur, plus the floor.
    const double blur_factor = 1.0 + c.covariance_blur_gain * appearance.blur_sigma_px;
    result->pose.covariance *= blur_factor * blur_factor;
    addCovarianceFloor(result->pose.translation.norm(), &result->pose.covariance);
  }
  addFaceScaleBias(camera_, model_.faceCorners(), c.face_scale_bias_px, &result->pose);
  return {};
}

StageOutcome MonoPoseEstimator::vetFivePointPose(const MarkerPixels& predicted, const MarkerPixels& located, double radius_px,
                                         const std::vector<Eigen::Vector3d>& model_points,
                                         const std::vector<Eigen::Vector2d>& image_points,
                                         MonoPoseResult* result) const {
  // A dot that is not where the face's homography puts it is something else (a card edge, a shadow).
  const double max_offset = std::max(1.5, kMaxDotOffsetRadii * radius_px);
  for (int i = 0; i < kMarkerCount; ++i) {
    const double offset = (located[static_cast<size_t>(i)] - predicted[static_cast<size_t>(i)]).norm();
    if (offset > max_offset) {
      return refuse(result, outcomeOf(Stage::kVet, VetOutcome::kDotOffset), RejectReason::kDotAppearance,
                    "marker " + std::to_string(i) + " found " + std::to_string(offset) +
                        " px from where the face puts it");
    }
  }
  PlanarPnpSolution pnp;
  std::string reason;
  if (!pnp_solver_.solve(camera_, model_points, image_points, &result->pose.rotation, &pnp, &reason)) return {};
  const double disagreement_deg = rotationAngleBetween(pnp.pose.rotation, result->pose.rotation) * 180.0 / M_PI;
  if (disagreement_deg > kMaxSolverDisagreementDeg) {
    return refuse(result, outcomeOf(Stage::kVet, VetOutcome::kSolverDisagreement), RejectReason::kSolverDisagreement,
                  "the 5-point pose and the face's PnP pose differ by " + std::to_string(disagreement_deg) +
                      " deg");
  }
  return {};
}

bool MonoPoseEstimator::vetLedBlobs(const std::vector<LedBlob>& blobs, const LedPatternCandidate& candidate,
                                    std::string* reason) const {
  std::vector<double> areas;
  for (const int index : candidate.blob_indices) areas.push_back(blobs[static_cast<size_t>(index)].area_px);
  std::vector<double> sorted = areas;
  std::sort(sorted.begin(), sorted.end());
  const double median_area = sorted[sorted.size() / 2];
  for (size_t i = 0; i < candidate.blob_indices.size(); ++i) {
    const LedBlob& blob = blobs[static_cast<size_t>(candidate.blob_indices[i])];
    if (blob.area_px > kMaxLedAreaRatio * median_area) {
      *reason = "LED " + std::to_string(i) + " blob is " + std::to_string(blob.area_px / median_area) +
                " times the others' area: merged with a reflection";
      return false;
    }
    if (blob.elongation > kMaxLedElongation) {
      *reason = "LED " + std::to_string(i) + " blob is elongated (" + std::to_string(blob.elongation) +
                "): merged with a reflection";
      return false;
    }
  }
  return true;
}

}  // namespace mono
}  // namespace docking_perception
