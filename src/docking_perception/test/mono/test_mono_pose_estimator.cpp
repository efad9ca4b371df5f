#include <gtest/gtest.h>

#include <Eigen/Eigenvalues>
#include <opencv2/core.hpp>
#include <set>
#include <string>
#include <utility>
#include <vector>

#include "docking_perception/debug_caption.h"
#include "docking_perception/mono/debug_drawing.h"
#include "docking_perception/mono/mono_pose_estimator.h"
#include "docking_settings/yaml_loader.h"
#include "synthetic_scene.h"

using namespace docking_perception::mono;  // NOLINT: test file

namespace {

double degrees(double rad) { return rad * 180.0 / M_PI; }

struct ViewCase {
  double yaw;
  double pitch;
  Eigen::Vector3d t;
};

// The shipped configuration of the mode (config/mono_pose_<mode>.yaml) with the solver under test.
MonoPoseParams paramsFor(MonoMode mode, PoseSolverType solver) {
  MonoPoseParams params = docking_settings::shippedSettings<MonoPoseNodeSettings>(
                              std::string(CONFIG_DIR) + "/mono_pose_" + toString(mode) + ".yaml")
                              .core;
  params.solver = toString(solver);
  return params;
}

// The key of the first setting validate() refuses; empty when it accepts them.
std::string refusedKey(const MonoPoseParams& params) {
  try {
    validate(params);
  } catch (const docking_settings::ConfigError& e) {
    return e.key();
  }
  return "";
}

}  // namespace

// End to end on synthetic views: the texture warped into a 640x480 image with the plane's homography.
// Tolerances: PnP over ~100+ inliers is expected at the goal (0.5 % of range, 0.5 deg); we assert
// 1 % and 1 deg for margin over rendering effects. The 5-point solver rests on 5 dots located to a few
// tenths of a pixel, so its tilt error is several degrees (see test_five_point_solver); we assert 2 % of
// range and 6 deg.
TEST(MonoPoseEstimator, VisibleViewsGiveThePoseWithBothSolvers) {
  const TargetModel model = synthetic::makeModel(1);
  const CameraIntrinsics camera = synthetic::defaultCamera();
  const std::vector<ViewCase> views = {{0.0, 0.0, {0.0, 0.0, 1.0}},
                                       {0.35, 0.1, {0.05, -0.03, 0.7}},
                                       {-0.5, 0.0, {-0.05, 0.02, 1.4}},
                                       {0.2, -0.15, {0.0, 0.0, 0.45}}};
  for (const PoseSolverType solver : {PoseSolverType::kPnp, PoseSolverType::kPaperFivePoint}) {
    for (size_t v = 0; v < views.size(); ++v) {
      const ViewCase& view = views[v];
      MonoPoseEstimator estimator(model, camera, paramsFor(MonoMode::kVisible, solver));
      const Eigen::Matrix3d r = synthetic::facingRotation(view.yaw, view.pitch);
      const cv::Mat image = synthetic::renderVisible(model, camera, r, view.t, 100 + v);
      const MonoPoseResult result = estimator.process(image, 1.0);
      ASSERT_TRUE(result.valid) << toString(solver) << " view " << v << ": " << result.status;
      const double range = view.t.norm();
      const double position_error = (result.pose.translation - view.t).norm();
      const double angle_error = degrees(rotationAngleBetween(result.pose.rotation, r));
      const bool pnp = solver == PoseSolverType::kPnp;
      EXPECT_LT(position_error, (pnp ? 0.01 : 0.02) * range) << toString(solver) << " view " << v;
      EXPECT_LT(angle_error, pnp ? 1.0 : 6.0) << toString(solver) << " view " << v;
      EXPECT_EQ(result.solver, toString(solver));
      EXPECT_GE(result.feature_inliers, 12);
      EXPECT_GE(result.feature_matches, result.feature_inliers);
      EXPECT_LT(result.reprojection_error_px, 1.5);
      EXPECT_NEAR(result.range_m, result.pose.translation.norm(), 1e-12);
      EXPECT_EQ(result.face_outline.size(), 4u);
      EXPECT_GT(result.processing_time_ms, 0.0);
      // A real covariance: positive definite, a depth sigma between 10 um and 10 cm (PnP at 0.45 m
      // claims ~0.07 mm, the 5-point solver at 1.4 m ~7 cm).
      Eigen::SelfAdjointEigenSolver<Matrix6d> eigen(result.pose.covariance);
      EXPECT_GT(eigen.eigenvalues().minCoeff(), 0.0);
      EXPECT_GT(std::sqrt(result.pose.covariance(2, 2)), 1e-5);
      EXPECT_LT(std::sqrt(result.pose.covariance(2, 2)), 0.1);
      EXPECT_FALSE(result.twist.valid);  // one pose: no velocity yet
      if (!pnp) {
        EXPECT_EQ(result.marker_pixels.size(), 5u);
      }
    }
  }
}

// confirm_new_orientation (off by default): the first pose of a track claims its position only; the next
// frame, checked against it, claims its orientation. After a gap longer than the filter's, the next pose
// is a first pose again. Off, the first pose claims its orientation at once.
TEST(MonoPoseEstimator, AFirstOrientationIsClaimedOnlyOnceTheNextFrameConfirmsIt) {
  const TargetModel model = synthetic::makeModel(2);
  const CameraIntrinsics camera = synthetic::defaultCamera();
  const Eigen::Matrix3d rotation = synthetic::facingRotation(0.2);
  const Eigen::Vector3d position(0.02, 0.0, 0.9);
  const cv::Mat image = synthetic::renderVisible(model, camera, rotation, position, 310);
  MonoPoseParams params = paramsFor(MonoMode::kVisible, PoseSolverType::kPnp);
  params.consistency.confirm_new_orientation = true;
  MonoPoseEstimator estimator(model, camera, params);
  const MonoPoseResult first = estimator.process(image, 10.0);
  ASSERT_TRUE(first.valid) << first.status;
  EXPECT_FALSE(first.orientation_valid);
  EXPECT_FALSE(first.rotation_innovation_checked);
  EXPECT_NE(first.status.find("confirm_new_orientation"), std::string::npos) << first.status;
  const MonoPoseResult second = estimator.process(image, 10.0 + 1.0 / 30.0);
  ASSERT_TRUE(second.valid) << second.status;
  EXPECT_TRUE(second.rotation_innovation_checked);
  EXPECT_TRUE(second.orientation_valid) << second.status;
  EXPECT_LT(degrees(rotationAngleBetween(second.pose.rotation, rotation)), 1.0);
  const MonoPoseResult after_gap = estimator.process(image, 10.1 + 2.0 * params.filter.max_gap_s);
  ASSERT_TRUE(after_gap.valid) << after_gap.status;
  EXPECT_FALSE(after_gap.orientation_valid);

  params.consistency.confirm_new_orientation = false;
  MonoPoseEstimator unconfirmed(model, camera, params);
  const MonoPoseResult at_once = unconfirmed.process(image, 10.0);
  ASSERT_TRUE(at_once.valid) << at_once.status;
  EXPECT_TRUE(at_once.orientation_valid) << at_once.status;
}

TEST(MonoPoseEstimator, TrackingUsesThePredictedRegionAndGivesAVelocity) {
  const TargetModel model = synthetic::makeModel(2);
  const CameraIntrinsics camera = synthetic::defaultCamera();
  MonoPoseEstimator estimator(model, camera, paramsFor(MonoMode::kVisible, PoseSolverType::kPnp));
  const Eigen::Vector3d velocity(0.02, 0.0, -0.05);
  MonoPoseResult result;
  for (int frame = 0; frame < 20; ++frame) {
    const double t = frame / 30.0;
    const Eigen::Vector3d position = Eigen::Vector3d(0.0, 0.0, 1.0) + velocity * t;
    const cv::Mat image = synthetic::renderVisible(model, camera, synthetic::facingRotation(0.2), position, 300 + frame);
    result = estimator.process(image, 10.0 + t);
    ASSERT_TRUE(result.valid) << "frame " << frame << ": " << result.status;
    if (frame == 0) {
      EXPECT_FALSE(result.used_tracking_region);
    } else {
      EXPECT_TRUE(result.used_tracking_region) << "frame " << frame;
      EXPECT_LT(result.search_region.area(), camera.width * camera.height / 2);
    }
  }
  ASSERT_TRUE(result.twist.valid);
  ASSERT_TRUE(result.twist_frame_difference.valid);
  EXPECT_LT((result.twist.linear - velocity).norm(), 0.05);

  // The paper's velocity, kept for comparison (velocity_method frame_difference): the one published.
  MonoPoseParams paper = paramsFor(MonoMode::kVisible, PoseSolverType::kPnp);
  paper.velocity_method = "frame_difference";
  MonoPoseEstimator differencing(model, camera, paper);
  for (int frame = 0; frame < 3; ++frame) {
    const double t = frame / 30.0;
    const Eigen::Vector3d position = Eigen::Vector3d(0.0, 0.0, 1.0) + velocity * t;
    result = differencing.process(synthetic::renderVisible(model, camera, synthetic::facingRotation(0.2), position, 300 + frame),
                                  10.0 + t);
    ASSERT_TRUE(result.valid) << "frame " << frame << ": " << result.status;
  }
  ASSERT_TRUE(result.twist.valid) << result.velocity_status;
  EXPECT_EQ(result.twist.linear, result.twist_frame_difference.linear);
  EXPECT_EQ(result.twist.angular, result.twist_frame_difference.angular);
  EXPECT_LT((result.twist.linear - velocity).norm(), 0.2);  // one difference of two poses: noisier
}

// Tracking without features (issue 15): after the first image, the face is refined where the filter
// predicts it (no feature search) and the pose is as accurate; when the target jumps where the prediction
// cannot follow, the feature search finds it in the same image; with the option off, every image searches.
TEST(MonoPoseEstimator, TracksAtThePredictedFaceAndSearchesWhenThePredictionFails) {
  const TargetModel model = synthetic::makeModel(2);
  const CameraIntrinsics camera = synthetic::defaultCamera();
  MonoPoseParams params = paramsFor(MonoMode::kVisible, PoseSolverType::kPnp);
  params.filter.gate_chi2 = 0.0;  // the jump below is the point: no filter gate
  MonoPoseEstimator estimator(model, camera, params);
  params.predict_face_when_tracking = false;
  MonoPoseEstimator searching(model, camera, params);
  const Eigen::Vector3d velocity(0.03, 0.0, -0.06);
  int predicted = 0;
  for (int frame = 0; frame < 15; ++frame) {
    const double t = frame / 30.0;
    const Eigen::Vector3d position = Eigen::Vector3d(-0.02, 0.01, 1.0) + velocity * t;
    const Eigen::Matrix3d rotation = synthetic::facingRotation(0.2 + 0.3 * t, 0.05);
    const cv::Mat image = synthetic::renderVisible(model, camera, rotation, position, 400 + frame);
    const MonoPoseResult result = estimator.process(image, 10.0 + t);
    const MonoPoseResult reference = searching.process(image, 10.0 + t);
    ASSERT_TRUE(result.valid) << "frame " << frame << ": " << result.status;
    ASSERT_TRUE(reference.valid) << "frame " << frame << ": " << reference.status;
    EXPECT_FALSE(reference.used_predicted_face);
    if (frame == 0) {
      EXPECT_FALSE(result.used_predicted_face);
    }
    predicted += result.used_predicted_face ? 1 : 0;
    if (result.used_predicted_face) {
      EXPECT_EQ(result.feature_matches, 0);  // no feature search ran
      EXPECT_TRUE(result.used_tracking_region);
    }
    EXPECT_LT((result.pose.translation - position).norm(), 0.01 * position.norm()) << "frame " << frame;
    EXPECT_LT(degrees(rotationAngleBetween(result.pose.rotation, rotation)), 1.0) << "frame " << frame;
  }
  EXPECT_GE(predicted, 12);
  // The target 8 cm to the side at once (~44 px): the prediction does not hold, the search finds it.
  const Eigen::Vector3d jumped = Eigen::Vector3d(0.06, 0.01, 0.97);
  const Eigen::Matrix3d rotation = synthetic::facingRotation(0.35, 0.05);
  const MonoPoseResult after_jump =
      estimator.process(synthetic::renderVisible(model, camera, rotation, jumped, 499), 10.5);
  ASSERT_TRUE(after_jump.valid) << after_jump.status;
  EXPECT_FALSE(after_jump.used_predicted_face);
  // The image's own pose: with the gate off the filter fuses the jump with the track before it.
  EXPECT_LT((after_jump.measured_pose.translation - jumped).norm(), 0.01);
}

// The published orientation is the velocity filter's posterior (publish_filtered_orientation): on a still
// target seen through noise, from the second image on it is the filter's and the position the image's
// own; the orientation moves less from image to image than the images' own, is no farther from the truth
// on average, and its variance is below the image's own. With the option off, the image's own pose is
// published. A jump the filter's gate refuses publishes the image's own pose.
TEST(MonoPoseEstimator, ThePublishedOrientationIsTheFiltersPosterior) {
  const TargetModel model = synthetic::makeModel(5);
  const CameraIntrinsics camera = synthetic::defaultCamera();
  MonoPoseParams params = paramsFor(MonoMode::kVisible, PoseSolverType::kPnp);
  MonoPoseEstimator filtered(model, camera, params);
  params.publish_filtered_orientation = false;
  MonoPoseEstimator unfiltered(model, camera, params);
  const Eigen::Vector3d position(0.05, -0.03, 1.7);
  const Eigen::Matrix3d rotation = synthetic::facingRotation(0.25, 0.1);
  constexpr double kNoiseDn = 24.0;
  // Image to image, the published orientation moves less than the images' own (the truth is still), and
  // on average it is no farther from the truth (the rendering's own bias, ~0.15 deg, stays in both).
  double published_step_deg = 0.0;
  double measured_step_deg = 0.0;
  double published_error_deg = 0.0;
  double measured_error_deg = 0.0;
  MonoPoseResult previous;
  int compared = 0;
  for (int frame = 0; frame < 40; ++frame) {
    const cv::Mat image = synthetic::renderVisible(model, camera, rotation, position, 700 + frame, kNoiseDn);
    const double stamp = 20.0 + frame / 30.0;
    const MonoPoseResult result = filtered.process(image, stamp);
    const MonoPoseResult reference = unfiltered.process(image, stamp);
    ASSERT_TRUE(result.valid) << "frame " << frame << ": " << result.status;
    ASSERT_TRUE(reference.valid) << "frame " << frame << ": " << reference.status;
    EXPECT_FALSE(reference.orientation_filtered);
    EXPECT_LT((reference.pose.translation - reference.measured_pose.translation).norm(), 1e-12);
    EXPECT_EQ(result.orientation_filtered, frame >= 1) << "frame " << frame;
    if (frame >= 10) {
      // Both estimators saw the same images and fed the same filter: the images' own poses are equal.
      EXPECT_LT((result.measured_pose.translation - reference.pose.translation).norm(), 1e-9);
      EXPECT_LT(result.pose.covariance(3, 3), result.measured_pose.covariance(3, 3)) << "frame " << frame;
      EXPECT_LT((result.pose.translation - result.measured_pose.translation).norm(), 1e-12) << "frame " << frame;
      EXPECT_EQ(result.pose.covariance(0, 0), result.measured_pose.covariance(0, 0)) << "frame " << frame;
      published_step_deg += degrees(rotationAngleBetween(result.pose.rotation, previous.pose.rotation));
      measured_step_deg += degrees(rotationAngleBetween(result.measured_pose.rotation, previous.measured_pose.rotation));
      published_error_deg += degrees(rotationAngleBetween(result.pose.rotation, rotation));
      measured_error_deg += degrees(rotationAngleBetween(result.measured_pose.rotation, rotation));
      ++compared;
    }
    previous = result;
  }
  ASSERT_EQ(compared, 30);
  EXPECT_LT(published_step_deg, 0.5 * measured_step_deg)
      << "mean step between images: published " << published_step_deg / compared << " deg, measured "
      << measured_step_deg / compared << " deg";
  EXPECT_LT(published_error_deg, measured_error_deg);
  // The target 10 cm to the side at once: the gate refuses it, the image's own pose is published.
  const Eigen::Vector3d jumped = position + Eigen::Vector3d(0.10, 0.0, 0.0);
  const MonoPoseResult after_jump =
      filtered.process(synthetic::renderVisible(model, camera, rotation, jumped, 799, kNoiseDn), 21.5);
  ASSERT_TRUE(after_jump.valid) << after_jump.status;
  EXPECT_FALSE(after_jump.orientation_filtered);
  EXPECT_LT((after_jump.pose.translation - jumped).norm(), 0.01);
}

// The disparity detector's position of the same target (the position hint) checks the pose while fresh
// and in the stereo range: a pose whose range is 8 % off the hint's is not valid (the code says why), one
// at the hint's range is, wherever the hint's bearing (a turning chaser moves it), and a stale hint, or
// one nearer than hint_check_min_range_m, checks nothing. Synthetic view at 1.2 m; max_hint_disagreement_fraction 0.04, hint_check_min_range_m set below the view's range (the
// default, 2 m, is the stereo range's start).
TEST(MonoPoseEstimator, APoseThatDisagreesWithAFreshPositionHintIsNotValid) {
  const TargetModel model = synthetic::makeModel(4);
  const CameraIntrinsics camera = synthetic::defaultCamera();
  MonoPoseParams params = paramsFor(MonoMode::kVisible, PoseSolverType::kPnp);
  params.consistency.max_hint_disagreement_fraction = 0.04;
  params.region_hint_max_age_s = 0.2;
  params.consistency.hint_check_min_range_m = 1.0;
  const Eigen::Vector3d t(0.05, -0.02, 1.2);
  const Eigen::Matrix3d r = synthetic::facingRotation(0.2, 0.0);
  const cv::Mat image = synthetic::renderVisible(model, camera, r, t, 140);
  struct HintCase {
    Eigen::Vector3d position;
    double age_s;
    bool valid;
  };
  const std::vector<HintCase> cases = {{t, 0.07, true},              // the stereo range agrees
                                       {1.08 * t, 0.07, false},      // 8 % farther along the ray
                                       // 6 % to the side at the same range: where a turning chaser
                                       // saw the target two frames ago; a scale bias is along the ray
                                       {t.norm() * (t + Eigen::Vector3d(0.07, 0.0, 0.0)).normalized(), 0.07, true},
                                       {0.92 * t + Eigen::Vector3d(0.07, 0.0, 0.0), 0.07, false},  // nearer and aside
                                       {1.08 * t, 0.5, true}};       // older than region_hint_max_age_s
  for (size_t i = 0; i < cases.size(); ++i) {
    MonoPoseEstimator estimator(model, camera, params);
    estimator.setPositionHint(cases[i].position, 2.0 - cases[i].age_s);
    const MonoPoseResult result = estimator.process(image, 2.0);
    EXPECT_EQ(result.valid, cases[i].valid) << "case " << i << ": " << result.status;
    EXPECT_EQ(result.reject_reason, cases[i].valid ? RejectReason::kNone : RejectReason::kHintDisagreement) << "case " << i;
  }
  params.consistency.hint_check_min_range_m = 2.0;  // the hint (1.3 m) is nearer: no check
  MonoPoseEstimator near(model, camera, params);
  near.setPositionHint(1.08 * t, 1.93);
  EXPECT_TRUE(near.process(image, 2.0).valid);
  params.consistency.max_hint_disagreement_fraction = 0.0;  // off
  MonoPoseEstimator unchecked(model, camera, params);
  unchecked.setPositionHint(1.08 * t, 1.93);
  EXPECT_TRUE(unchecked.process(image, 2.0).valid);
  params.consistency.max_hint_disagreement_fraction = 1.0;
  EXPECT_EQ(refusedKey(params), "max_hint_disagreement_fraction");
}

// After a pose disagreed with a fresh hint, a pose with no fresh hint to check it is refused for 1 s (a late
// disparity estimate let one through, campaign seed 10506), and one with a fresh hint must agree within half
// of max_hint_disagreement_fraction; a hint that agrees so ends the hold.
TEST(MonoPoseEstimator, ADisagreementHoldsUntilAHintAgreesOrTheHoldEnds) {
  const TargetModel model = synthetic::makeModel(4);
  const CameraIntrinsics camera = synthetic::defaultCamera();
  MonoPoseParams params = paramsFor(MonoMode::kVisible, PoseSolverType::kPnp);
  params.consistency.max_hint_disagreement_fraction = 0.04;
  params.consistency.hint_check_min_range_m = 1.0;
  params.region_hint_max_age_s = 0.2;
  const Eigen::Vector3d t(0.05, -0.02, 1.2);
  const cv::Mat image = synthetic::renderVisible(model, camera, synthetic::facingRotation(0.2, 0.0), t, 140);

  MonoPoseEstimator held(model, camera, params);
  held.setPositionHint(1.08 * t, 1.93);
  const MonoPoseResult refused = held.process(image, 2.0);
  EXPECT_EQ(refused.reject_reason, RejectReason::kHintDisagreement);
  EXPECT_EQ(refused.stage, Stage::kHint);
  EXPECT_EQ(refused.stage_outcome, static_cast<std::uint8_t>(HintOutcome::kRangeDisagrees));
  const MonoPoseResult unchecked = held.process(image, 2.5);  // the hint is 0.57 s old: not fresh
  EXPECT_FALSE(unchecked.valid);
  EXPECT_EQ(unchecked.reject_reason, RejectReason::kHintDisagreement);
  EXPECT_EQ(unchecked.stage_outcome, static_cast<std::uint8_t>(HintOutcome::kHeldWithoutHint));
  const MonoPoseResult after_hold = held.process(image, 3.2);  // 1.2 s after the disagreement
  EXPECT_TRUE(after_hold.valid) << after_hold.status;

  // Within the hold, a hint 3 % off (inside max_hint_disagreement_fraction) is not enough to trust the pose
  // again; past the hold it is.
  MonoPoseEstimator hysteresis(model, camera, params);
  hysteresis.setPositionHint(1.08 * t, 1.93);
  EXPECT_FALSE(hysteresis.process(image, 2.0).valid);
  hysteresis.setPositionHint(1.03 * t, 2.35);
  const MonoPoseResult near_miss = hysteresis.process(image, 2.4);
  EXPECT_FALSE(near_miss.valid);
  EXPECT_EQ(near_miss.stage_outcome, static_cast<std::uint8_t>(HintOutcome::kNotRecovered));
  hysteresis.setPositionHint(1.03 * t, 3.55);  // 1.2 s after the last refusal (2.4 s)
  EXPECT_TRUE(hysteresis.process(image, 3.6).valid);

  MonoPoseEstimator cleared(model, camera, params);
  cleared.setPositionHint(1.08 * t, 1.93);
  EXPECT_FALSE(cleared.process(image, 2.0).valid);
  cleared.setPositionHint(t, 2.35);
  EXPECT_TRUE(cleared.process(image, 2.4).valid);  // a fresh hint that agrees ...
  const MonoPoseResult after_agreement = cleared.process(image, 2.9);
  EXPECT_TRUE(after_agreement.valid) << after_agreement.status;  // ... ends the hold
}

TEST(MonoPoseEstimator, ReportsWhyNothingWasFound) {
  const TargetModel model = synthetic::makeModel(1);
  const CameraIntrinsics camera = synthetic::defaultCamera();
  MonoPoseEstimator estimator(model, camera, paramsFor(MonoMode::kVisible, PoseSolverType::kPnp));
  const cv::Mat blank(480, 640, CV_8UC1, cv::Scalar(90));
  MonoPoseResult result = estimator.process(blank, 1.0);
  EXPECT_FALSE(result.valid);
  EXPECT_FALSE(result.status.empty());
  result = estimator.process(cv::Mat(240, 320, CV_8UC1, cv::Scalar(0)), 2.0);
  EXPECT_FALSE(result.valid);
  EXPECT_NE(result.status.find("camera_info says 640x480"), std::string::npos) << result.status;
  result = estimator.process(cv::Mat(), 3.0);
  EXPECT_FALSE(result.valid);
  EXPECT_EQ(result.status, "empty image");
}

// The stage that decided is on every result (stages.h): the input stage for an unusable image, the find
// stage when nothing is found, and for a valid pose the orientation stage while its orientation is withheld
// (a first pose: confirm_new_orientation), then the last stage, passed, once the next frame confirms it.
TEST(MonoPoseEstimator, EachResultCarriesTheStageThatDecided) {
  const TargetModel model = synthetic::makeModel(1);
  const CameraIntrinsics camera = synthetic::defaultCamera();
  MonoPoseEstimator estimator(model, camera, paramsFor(MonoMode::kVisible, PoseSolverType::kPnp));
  auto decided = [](const MonoPoseResult& r) {
    return std::string(stageName(r.stage)) + "/" + outcomeName(r.stage, r.stage_outcome);
  };
  EXPECT_EQ(decided(estimator.process(cv::Mat(), 1.0)), "input/empty");
  EXPECT_EQ(decided(estimator.process(cv::Mat(240, 320, CV_8UC1, cv::Scalar(0)), 1.1)), "input/wrong_size");
  EXPECT_EQ(decided(estimator.process(cv::Mat(480, 640, CV_16UC1, cv::Scalar(0)), 1.2)), "input/wrong_type");
  const MonoPoseResult blank = estimator.process(cv::Mat(480, 640, CV_8UC1, cv::Scalar(90)), 1.3);
  EXPECT_EQ(decided(blank), "find/face_not_found");
  EXPECT_EQ(blank.reject_reason, RejectReason::kNotFound);
  const Eigen::Matrix3d rotation = synthetic::facingRotation(0.2);
  const Eigen::Vector3d position(0.0, 0.0, 0.8);
  const MonoPoseResult first = estimator.process(synthetic::renderVisible(model, camera, rotation, position, 7), 2.0);
  ASSERT_TRUE(first.valid) << first.status;
  EXPECT_EQ(decided(first), "orientation/unconfirmed");
  const MonoPoseResult second =
      estimator.process(synthetic::renderVisible(model, camera, rotation, position, 8), 2.0 + 1.0 / 30.0);
  ASSERT_TRUE(second.valid) << second.status;
  EXPECT_EQ(decided(second), "position/claimed");

  MonoPoseEstimator ir(model, camera, paramsFor(MonoMode::kIr, PoseSolverType::kPnp));
  EXPECT_EQ(decided(ir.process(cv::Mat(480, 640, CV_8UC1, cv::Scalar(20)), 1.0)), "find/no_led_pattern");
}

// Every stage and outcome of stages.h has its name; a code a stage does not have is "unknown".
TEST(MonoStages, EveryOutcomeIsNamed) {
  const std::vector<std::pair<Stage, int>> outcome_counts = {
      {Stage::kInput, 7}, {Stage::kFind, 5},        {Stage::kSolve, 5}, {Stage::kVet, 5},      {Stage::kInnerPattern, 2},
      {Stage::kHint, 4},  {Stage::kOrientation, 5}, {Stage::kTrack, 1}, {Stage::kPosition, 2}};
  std::set<std::string> stage_names;
  for (const auto& [stage, count] : outcome_counts) {
    stage_names.insert(stageName(stage));
    std::set<std::string> names;
    for (int code = 0; code < count; ++code) names.insert(outcomeName(stage, static_cast<std::uint8_t>(code)));
    EXPECT_EQ(names.size(), static_cast<size_t>(count)) << stageName(stage);
    EXPECT_EQ(names.count("unknown"), 0u) << stageName(stage);
    EXPECT_STREQ(outcomeName(stage, static_cast<std::uint8_t>(count)), "unknown") << stageName(stage);
  }
  EXPECT_EQ(stage_names.size(), outcome_counts.size());
  EXPECT_EQ(static_cast<int>(kLastStage), static_cast<int>(outcome_counts.size()));
}

TEST(MonoPoseEstimator, IrModeFindsTheLedsInTheDark) {
  const TargetModel model = synthetic::makeModel(1);
  CameraIntrinsics camera = synthetic::defaultCamera();
  camera.fx = camera.fy = 520.0;
  for (const PoseSolverType solver : {PoseSolverType::kPaperFivePoint, PoseSolverType::kPnp}) {
    MonoPoseEstimator estimator(model, camera, paramsFor(MonoMode::kIr, solver));
    const Eigen::Matrix3d r = synthetic::facingRotation(-0.3, 0.1, 0.05);
    const Eigen::Vector3d t(0.03, 0.01, 0.9);
    std::vector<Eigen::Vector3d> points;
    for (const auto& m : model.markers()) points.push_back(r * m + t);
    points.emplace_back(0.25, -0.15, 1.3);  // a stray light
    const MonoPoseResult result = estimator.process(synthetic::renderLedSpots(camera, points, 0.005, 5), 1.0);
    ASSERT_TRUE(result.valid) << toString(solver) << ": " << result.status;
    EXPECT_EQ(result.feature_matches, 6);
    EXPECT_EQ(result.feature_inliers, 5);
    EXPECT_LT((result.pose.translation - t).norm(), 0.02 * t.norm()) << toString(solver);
    EXPECT_LT(degrees(rotationAngleBetween(result.pose.rotation, r)), 6.0) << toString(solver);
    // One LED hidden: a clean failure with the reason.
    points.erase(points.begin() + 3);
    const MonoPoseResult hidden = estimator.process(synthetic::renderLedSpots(camera, points, 0.005, 6), 1.1);
    EXPECT_FALSE(hidden.valid);
    EXPECT_NE(hidden.status.find("LED"), std::string::npos) << hidden.status;
  }
}

// Motion smears each LED into a streak whose centroid moves by an amount the five points' residual cannot
// show (eval_real_motion9px_1m: one IR frame 7.6 deg off with a 1.3 deg sigma): the streaks beyond a still
// spot's scale the covariance, as the visible blur does.
TEST(MonoPoseEstimator, IrCovarianceGrowsWithTheLedStreaks) {
  const TargetModel model = synthetic::makeModel(1);
  CameraIntrinsics camera = synthetic::defaultCamera();
  camera.fx = camera.fy = 520.0;
  const Eigen::Matrix3d r = synthetic::facingRotation(-0.3, 0.1, 0.05);
  const Eigen::Vector3d t(0.03, 0.01, 0.9);
  // One exposure: the LEDs swept across the image by a turn of the camera about its y axis, summed over
  // sub-frames and clipped (an LED saturates the sensor).
  auto exposure = [&](double smear_px) {
    constexpr int kSteps = 9;
    cv::Mat sum(camera.height, camera.width, CV_32F, cv::Scalar(0.0));
    for (int k = 0; k < kSteps; ++k) {
      const double angle = smear_px / camera.fx * (k / (kSteps - 1.0) - 0.5);
      const Eigen::Matrix3d turn = Eigen::AngleAxisd(angle, Eigen::Vector3d::UnitY()).toRotationMatrix();
      std::vector<Eigen::Vector3d> points;
      for (const auto& m : model.markers()) points.push_back(turn * (r * m + t));
      cv::Mat frame;
      synthetic::renderLedSpots(camera, points, 0.005, 7).convertTo(frame, CV_32F);
      sum += frame;
    }
    cv::Mat image;
    sum.convertTo(image, CV_8U, 3.0 / kSteps);
    return image;
  };
  const MonoPoseParams params = paramsFor(MonoMode::kIr, PoseSolverType::kPnp);
  MonoPoseEstimator sharp_estimator(model, camera, params);
  MonoPoseEstimator smeared_estimator(model, camera, params);
  const MonoPoseResult sharp = sharp_estimator.process(exposure(0.0), 1.0);
  const MonoPoseResult smeared = smeared_estimator.process(exposure(6.0), 1.0);
  ASSERT_TRUE(sharp.valid) << sharp.status;
  ASSERT_TRUE(smeared.valid) << smeared.status;
  EXPECT_EQ(sharp.blur_sigma_px, 0.0);
  // A 6 px streak: 6 / sqrt(12) = 1.7 px (a wide spot's sweep reads more), less the still 0.8 px in quadrature.
  EXPECT_GT(smeared.blur_sigma_px, 1.2);
  EXPECT_LT(smeared.blur_sigma_px, 3.2);
  const double sharp_rotation = sharp.pose.covariance.bottomRightCorner<3, 3>().trace();
  const double smeared_rotation = smeared.pose.covariance.bottomRightCorner<3, 3>().trace();
  EXPECT_GT(smeared_rotation, 3.0 * sharp_rotation) << smeared.blur_sigma_px;
}

// A pose whose position sigma is above max_position_sigma_fraction of its range is published not valid,
// with its code, but stays the tracked pose: the next image searches where it says the target is (were it
// dropped, the covariance's innovation scale that widened the sigma could never learn it had narrowed).
TEST(MonoPoseEstimator, AnUncertainPositionIsWithheldButStillTracked) {
  const TargetModel model = synthetic::makeModel(2);
  const CameraIntrinsics camera = synthetic::defaultCamera();
  const Eigen::Matrix3d rotation = synthetic::facingRotation(0.2);
  const Eigen::Vector3d position(0.02, 0.0, 1.2);
  MonoPoseParams params = paramsFor(MonoMode::kVisible, PoseSolverType::kPnp);
  params.consistency.position_sigma_check_max_range_m = 0.0;  // every range: the view is at 1.2 m, past the shipped 1 m
  MonoPoseEstimator unlimited(model, camera, params);
  const MonoPoseResult reference = unlimited.process(synthetic::renderVisible(model, camera, rotation, position, 320), 10.0);
  ASSERT_TRUE(reference.valid) << reference.status;
  const double largest_variance =
      Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d>(reference.pose.covariance.topLeftCorner<3, 3>()).eigenvalues().maxCoeff();
  const double sigma_fraction = std::sqrt(largest_variance) / reference.pose.translation.norm();
  ASSERT_GT(sigma_fraction, 0.0);

  params.consistency.max_position_sigma_fraction = 0.5 * sigma_fraction;
  MonoPoseEstimator strict(model, camera, params);
  for (int frame = 0; frame < 3; ++frame) {
    const MonoPoseResult result =
        strict.process(synthetic::renderVisible(model, camera, rotation, position, 320 + frame), 10.0 + frame / 30.0);
    EXPECT_FALSE(result.valid) << "frame " << frame;
    EXPECT_FALSE(result.orientation_valid) << "frame " << frame;
    EXPECT_EQ(result.reject_reason, RejectReason::kPositionUncertain) << "frame " << frame;
    EXPECT_EQ(result.stage, Stage::kPosition) << "frame " << frame;
    EXPECT_EQ(result.stage_outcome, static_cast<std::uint8_t>(PositionOutcome::kUncertain)) << "frame " << frame;
    EXPECT_NE(result.status.find("max_position_sigma_fraction"), std::string::npos) << result.status;
    EXPECT_EQ(result.used_tracking_region, frame > 0) << "frame " << frame << ": still tracked";
  }
  params.consistency.max_position_sigma_fraction = 2.0 * sigma_fraction;
  MonoPoseEstimator loose(model, camera, params);
  const MonoPoseResult claimed = loose.process(synthetic::renderVisible(model, camera, rotation, position, 320), 10.0);
  EXPECT_TRUE(claimed.valid) << claimed.status;
}

TEST(MonoPoseEstimator, InvalidParametersAreNamed) {
  MonoPoseParams params;
  params.features.fast_threshold = 0;
  EXPECT_EQ(refusedKey(params), "fast_threshold");
  EXPECT_THROW(MonoPoseEstimator(synthetic::makeModel(1), synthetic::defaultCamera(), params), std::invalid_argument);
  EXPECT_EQ(refusedKey(MonoPoseParams()), "");
  MonoMode mode;
  EXPECT_TRUE(parseMonoMode("ir", &mode));
  EXPECT_EQ(mode, MonoMode::kIr);
  EXPECT_FALSE(parseMonoMode("thermal", &mode));
}

TEST(DebugDrawing, DrawsTheProjectedModelOnlyForAValidPose) {
  const TargetModel model = synthetic::makeModel(1);
  const CameraIntrinsics camera = synthetic::defaultCamera();
  MonoPoseEstimator estimator(model, camera, MonoPoseParams());
  const cv::Mat image =
      synthetic::renderVisible(model, camera, synthetic::facingRotation(0.2), Eigen::Vector3d(0.0, 0.0, 1.0), 1);
  const MonoPoseResult found = estimator.process(image, 1.0);
  ASSERT_TRUE(found.valid) << found.status;
  const cv::Mat drawn = drawDebugImage(image, found, camera, model);
  ASSERT_EQ(drawn.type(), CV_8UC3);
  ASSERT_EQ(drawn.size(), image.size());
  // The target's y axis is drawn in green: halfway along it the pixel is green.
  const Eigen::Vector2d origin = camera.project(found.pose.translation);
  const Eigen::Vector2d on_y_axis = camera.project(found.pose.rotation * Eigen::Vector3d(0.0, 0.06, 0.0) +
                                                   found.pose.translation);
  const cv::Vec3b green = drawn.at<cv::Vec3b>(cvRound(on_y_axis.y()), cvRound(on_y_axis.x()));
  EXPECT_GT(green[1], 150);
  EXPECT_LT(green[2], 100);
  // Nothing found: no pose drawn, the gray image comes back as colour with only the status text.
  MonoPoseResult lost;
  lost.solver = "pnp";
  lost.status = "too few matches";
  const cv::Mat lost_drawn = drawDebugImage(image, lost, camera, model);
  const cv::Vec3b pixel = lost_drawn.at<cv::Vec3b>(cvRound(origin.y()), cvRound(origin.x()));
  EXPECT_EQ(pixel[0], pixel[1]);
  EXPECT_EQ(pixel[1], pixel[2]);
}

// The debug images' caption (issue 54: unreadable at rviz's panel size): a font that scales with the image,
// wrapped at spaces to at most kMaxCaptionLines lines that fit the width, on a darkened band at the top;
// the image below the band untouched.
TEST(DebugCaption, WrapsToFitAndLeavesTheImageBelowAlone) {
  const std::string text =
      "no pose: too few matches (9 < 10); direct alignment: no prior (tracking or hint); far throttle off";
  const double scale = docking_perception::kCaptionScalePer640Px;
  const std::vector<std::string> lines = docking_perception::captionLines(text, scale, 2, 620);
  ASSERT_EQ(static_cast<int>(lines.size()), docking_perception::kMaxCaptionLines);
  EXPECT_EQ(lines.back().substr(lines.back().size() - 3), "...");
  int baseline = 0;
  for (std::size_t i = 0; i + 1 < lines.size(); ++i) {
    EXPECT_LE(cv::getTextSize(lines[i], cv::FONT_HERSHEY_SIMPLEX, scale, 2, &baseline).width, 620) << lines[i];
  }
  cv::Mat image(480, 640, CV_8UC3, cv::Scalar(200, 200, 200));
  docking_perception::drawCaption(image, "1.234 m  45 inliers", cv::Scalar(0, 255, 0));
  EXPECT_LT(image.at<cv::Vec3b>(2, 630)[0], 100);            // the band, darkened
  EXPECT_EQ(image.at<cv::Vec3b>(400, 320), cv::Vec3b(200, 200, 200));  // below it, as it was
  int green = 0;  // the text, drawn in the band at a readable size
  for (int row = 0; row < 120; ++row) {
    for (int col = 0; col < 640; ++col) {
      const cv::Vec3b pixel = image.at<cv::Vec3b>(row, col);
      green += pixel[1] > 200 && pixel[2] < 100;
    }
  }
  EXPECT_GT(green, 2000);
}
