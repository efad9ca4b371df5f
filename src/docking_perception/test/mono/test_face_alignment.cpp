// gtests of the direct (ECC) face alignment (face_alignment.h) on docking_sim's renders with the stress
// harness's blur and noise. Fixed seeds 300-311 (neither the tuning range 100-139 nor the report ranges).
#include <gtest/gtest.h>

#include <Eigen/Geometry>
#include <cmath>
#include <random>
#include <string>

#include "docking_perception/mono/face_alignment.h"
#include "docking_perception/mono/pose_consistency.h"
#include "mono_stress.h"
#include "stress_fixtures.h"

namespace mono = docking_perception::mono;
namespace stress = docking_perception::stress;

namespace {

constexpr uint64_t kFirstSeed = 300;
constexpr int kTrials = 6;

using docking_perception::stress_test::condition;
using docking_perception::stress_test::model;
using docking_perception::stress_test::renderer;

mono::MonoPoseParams visibleParams() { return docking_perception::stress_test::params("visible"); }

mono::PoseWithCovariance toPose(const stress::TrialPose& trial) {
  mono::PoseWithCovariance pose;
  pose.rotation = trial.rotation;
  pose.translation = trial.translation;
  return pose;
}

// The truth moved the way a one-frame prediction misses: 2 deg about a random axis, 1.5 % of the range.
mono::PoseWithCovariance perturbed(const stress::TrialPose& truth, uint64_t seed) {
  std::mt19937_64 rng(seed);
  std::normal_distribution<double> normal(0.0, 1.0);
  const Eigen::Vector3d axis = Eigen::Vector3d(normal(rng), normal(rng), normal(rng)).normalized();
  const Eigen::Vector3d shift = Eigen::Vector3d(normal(rng), normal(rng), normal(rng)).normalized();
  mono::PoseWithCovariance pose = toPose(truth);
  pose.rotation = Eigen::AngleAxisd(2.0 * M_PI / 180.0, axis).toRotationMatrix() * pose.rotation;
  pose.translation += 0.015 * truth.translation.norm() * shift;
  return pose;
}

// Largest distance (image px) between the face corners through the homography and the true ones.
double cornerError(const cv::Matx33d& homography, const stress::TrialPose& truth) {
  const cv::Matx33d true_homography = mono::faceHomography(model(), renderer().camera(), toPose(truth));
  const cv::Size size = model().textureGray().size();
  double worst = 0.0;
  for (const cv::Point2d& c : {cv::Point2d(0, 0), cv::Point2d(size.width, 0), cv::Point2d(size.width, size.height),
                               cv::Point2d(0, size.height)}) {
    const cv::Vec3d a = homography * cv::Vec3d(c.x, c.y, 1.0);
    const cv::Vec3d b = true_homography * cv::Vec3d(c.x, c.y, 1.0);
    worst = std::max(worst, std::hypot(a[0] / a[2] - b[0] / b[2], a[1] / a[2] - b[1] / b[2]));
  }
  return worst;
}

// Measured on these seeds, with the face textured bilinearly as docking_sim draws it: 6 of 6 align under
// 2 px defocus + 8 DN over clutter and under 9 px motion (3 and 5 of 6 before the coarse slide and the
// affine fallback: ECC gave up at its coarsest level), corners within 2 % of the face's width at 0.8 m.
void expectRecovered(const std::string& name) {
  const stress::StressCondition c = condition(name);
  const mono::DirectFaceAligner aligner(model(), visibleParams().direct);
  int found = 0;
  for (int t = 0; t < kTrials; ++t) {
    const uint64_t seed = kFirstSeed + static_cast<uint64_t>(t);
    const stress::TrialPose truth = renderer().drawPose(c, seed);
    const stress::StressFrame frame = renderer().render(c, truth, seed, seed * 16);
    const mono::PoseWithCovariance prior = perturbed(truth, seed);
    const double prior_error = cornerError(mono::faceHomography(model(), renderer().camera(), prior), truth);
    const mono::DirectAlignment result = aligner.align(frame.gray, renderer().camera(), prior);
    if (!result.found) continue;
    ++found;
    EXPECT_GE(result.correlation, visibleParams().direct.min_correlation);
    // The prior's corners are off by many pixels; the aligned ones within 2.5 % of the face's width.
    const double face_width_px = renderer().camera().fx * model().faceWidth() / truth.translation.z();
    EXPECT_GT(prior_error, 4.0) << "seed " << seed;
    EXPECT_LT(cornerError(result.homography, truth), 0.025 * face_width_px)
        << name << " seed " << seed << " range " << truth.translation.norm() << " prior error " << prior_error;
    EXPECT_EQ(result.image_points.size(), result.texture_points.size());
    EXPECT_GT(result.pixel_sigma_px, 0.0);
  }
  EXPECT_GE(found, kTrials - 1) << name;
}

}  // namespace

TEST(DirectFaceAlignment, RecoversTheFaceUnderDefocusFromAPerturbedPrior) { expectRecovered("clutter_defocus2_noise8"); }

TEST(DirectFaceAlignment, RecoversTheFaceUnderMotionBlurFromAPerturbedPrior) { expectRecovered("motion9"); }

// Under 2 px defocus, 9 px motion and 8 DN noise at any roll, the sharp template correlates with the face
// only just above direct_min_correlation (0.81-0.92 on seeds 300-311, where the stress harness's cold frames
// at 1.5-2 m fell to 0.71-0.79); blurred by the blur the appearance score measures at the prior (as the
// estimator does at the dots' pose), 0.88-0.99 on every seed, its corners within 4.5 % of the face's width.
TEST(DirectFaceAlignment, ATemplateBlurredAsTheImageCorrelatesUnderAllThreeBlurs) {
  const stress::StressCondition c = condition("roll_any_defocus2_motion9_noise8");
  const mono::DirectFaceAligner aligner(model(), visibleParams().direct);
  const mono::FaceAppearance appearance(model());
  constexpr int kBlurTrials = 12;
  int sharp_found = 0, blurred_found = 0, higher = 0;
  for (int t = 0; t < kBlurTrials; ++t) {
    const uint64_t seed = kFirstSeed + static_cast<uint64_t>(t);
    const stress::TrialPose truth = renderer().drawPose(c, seed);
    const stress::StressFrame frame = renderer().render(c, truth, seed, seed * 16);
    const mono::PoseWithCovariance prior = perturbed(truth, seed);
    const cv::Matx33d initial = mono::faceHomography(model(), renderer().camera(), prior);
    const double blur_px = appearance.score(frame.gray, renderer().camera(), prior).blur_sigma_px;
    const mono::DirectAlignment sharp = aligner.align(frame.gray, initial);
    const mono::DirectAlignment blurred = aligner.align(frame.gray, initial, /*coarse_only=*/false, blur_px);
    std::printf("seed %llu range %.2f blur %.1f: sharp %d %.3f %.2f px, blurred %d %.3f %.2f px\n",
                static_cast<unsigned long long>(seed), truth.translation.norm(), blur_px, sharp.found ? 1 : 0,
                sharp.correlation, cornerError(sharp.homography, truth), blurred.found ? 1 : 0, blurred.correlation,
                cornerError(blurred.homography, truth));
    sharp_found += sharp.found ? 1 : 0;
    blurred_found += blurred.found ? 1 : 0;
    higher += blurred.correlation > sharp.correlation ? 1 : 0;
    if (blurred.found) {
      const double face_width_px = renderer().camera().fx * model().faceWidth() / truth.translation.z();
      EXPECT_LT(cornerError(blurred.homography, truth), 0.05 * face_width_px) << "seed " << seed;
    }
  }
  EXPECT_GE(blurred_found, sharp_found);
  EXPECT_GE(blurred_found, kBlurTrials - 1);
  EXPECT_GE(higher, kBlurTrials - 1);
}

// Where the prior puts the face there is only clutter (the target is out of view): no alignment may
// reach the correlation threshold.
TEST(DirectFaceAlignment, RefusesAnImageWithoutTheFace) {
  const stress::StressCondition c = condition("clutter_defocus2_noise8");
  const mono::DirectFaceAligner aligner(model(), visibleParams().direct);
  for (int t = 0; t < kTrials; ++t) {
    const uint64_t seed = kFirstSeed + static_cast<uint64_t>(t);
    const stress::TrialPose truth = renderer().drawPose(c, seed);
    stress::TrialPose away = truth;
    away.translation.x() += 20.0;  // far outside the view: the image is the room only
    const stress::StressFrame frame = renderer().render(c, away, seed, seed * 16);
    const mono::DirectAlignment result = aligner.align(frame.gray, renderer().camera(), toPose(truth));
    EXPECT_FALSE(result.found) << "seed " << seed << " correlation " << result.correlation;
  }
  const mono::DirectAlignment flat =
      aligner.align(cv::Mat(480, 640, CV_8U, cv::Scalar(128)), renderer().camera(),
                    toPose(renderer().drawPose(c, kFirstSeed)));
  EXPECT_FALSE(flat.found);
}

// A prior that puts the face behind the camera or too small is refused before any alignment.
TEST(DirectFaceAlignment, RefusesUnusablePriors) {
  const mono::DirectFaceAligner aligner(model(), visibleParams().direct);
  mono::PoseWithCovariance behind = toPose(renderer().drawPose(condition("clean"), kFirstSeed));
  behind.translation.z() = -1.0;
  const cv::Mat image(480, 640, CV_8U, cv::Scalar(128));
  EXPECT_FALSE(aligner.align(image, renderer().camera(), behind).found);
  mono::PoseWithCovariance far = behind;
  far.translation = Eigen::Vector3d(0.0, 0.0, 30.0);
  const mono::DirectAlignment tiny = aligner.align(image, renderer().camera(), far);
  EXPECT_FALSE(tiny.found);
  EXPECT_NE(tiny.status.find("too small"), std::string::npos) << tiny.status;
}

// A face turned 53 deg at 3.4 m is 29 px wide: too few pixels for the homography's scale (seed 7699's
// campaign frames aligned 6 % small). From a prior turned 43 deg (35 px wide, accepted) the alignment
// is refused. The same face at 2 m (49 px wide) aligns, its corners within 2.5 % of its width.
TEST(DirectFaceAlignment, RefusesAFaceTooNarrowForItsScaleButNotOneInTheMonocularRange) {
  const mono::DirectFaceAligner aligner(model(), visibleParams().direct);
  Eigen::Matrix3d facing;
  facing.col(0) = Eigen::Vector3d(0, 0, -1);  // face normal (target x) towards the camera
  facing.col(1) = Eigen::Vector3d(1, 0, 0);
  facing.col(2) = Eigen::Vector3d(0, -1, 0);
  for (const double range : {3.4, 2.0}) {
    stress::TrialPose truth;
    truth.rotation = facing * Eigen::AngleAxisd(53.0 * M_PI / 180.0, Eigen::Vector3d::UnitZ()).toRotationMatrix();
    truth.translation = Eigen::Vector3d(0.0, 0.0, range);
    const stress::StressFrame frame = renderer().render(condition("clean"), truth, kFirstSeed, kFirstSeed * 16);
    mono::PoseWithCovariance prior;
    prior.rotation = facing * Eigen::AngleAxisd(43.0 * M_PI / 180.0, Eigen::Vector3d::UnitZ()).toRotationMatrix();
    prior.translation = truth.translation;
    const mono::DirectAlignment result = aligner.align(frame.gray, renderer().camera(), prior);
    const double face_width_px = renderer().camera().fx * model().faceWidth() / range;
    if (range > 3.0) {
      EXPECT_FALSE(result.found) << "correlation " << result.correlation;
    } else {
      ASSERT_TRUE(result.found) << result.status;
      EXPECT_LT(cornerError(result.homography, truth), 0.025 * face_width_px);
    }
  }
}
