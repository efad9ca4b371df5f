#include <gtest/gtest.h>

#include <cmath>
#include <opencv2/calib3d.hpp>
#include <opencv2/core.hpp>
#include <vector>

#include "docking_perception/mono/planar_pnp_solver.h"
#include "synthetic_scene.h"

using namespace docking_perception::mono;  // NOLINT: test file

namespace {

// Points spread over the face (x = 0), as feature matches would be.
std::vector<Eigen::Vector3d> facePoints(int count, double half_width, double half_height, uint64_t seed) {
  cv::RNG rng(seed);
  std::vector<Eigen::Vector3d> points;
  for (int i = 0; i < count; ++i) {
    points.emplace_back(0.0, rng.uniform(-half_width, half_width), rng.uniform(-half_height, half_height));
  }
  return points;
}

std::vector<Eigen::Vector2d> projectAll(const CameraIntrinsics& camera, const Eigen::Matrix3d& r,
                                        const Eigen::Vector3d& t, const std::vector<Eigen::Vector3d>& points,
                                        double noise, uint64_t seed) {
  cv::RNG rng(seed);
  std::vector<Eigen::Vector2d> pixels;
  for (const auto& p : points) {
    pixels.push_back(camera.project(r * p + t) + Eigen::Vector2d(rng.gaussian(noise), rng.gaussian(noise)));
  }
  return pixels;
}

}  // namespace

TEST(PlanarPnpSolver, RecoversThePoseFromManyNoisyPoints) {
  const CameraIntrinsics camera = synthetic::defaultCamera();
  const Eigen::Matrix3d r = synthetic::facingRotation(0.4, -0.2, 0.1);
  const Eigen::Vector3d t(0.05, -0.03, 1.0);
  const auto model = facePoints(150, 0.15, 0.12, 1);
  const auto pixels = projectAll(camera, r, t, model, 0.5, 2);
  PlanarPnpSolver solver;
  PlanarPnpSolution solution;
  std::string reason;
  ASSERT_TRUE(solver.solve(camera, model, pixels, nullptr, &solution, &reason)) << reason;
  // 150 points with 0.5 px noise: millimetres and a fraction of a degree.
  EXPECT_LT((solution.pose.translation - t).norm(), 0.005);
  EXPECT_LT(rotationAngleBetween(solution.pose.rotation, r) * 180.0 / M_PI, 0.5);
  EXPECT_NEAR(solution.reprojection_rms_px, 0.5 * std::sqrt(2.0), 0.15);
  // The covariance's position sigma is of the order of the real error (not zero, not huge).
  const double sigma_z = std::sqrt(solution.pose.covariance(2, 2));
  EXPECT_GT(sigma_z, 1e-4);
  EXPECT_LT(sigma_z, 0.01);
}

TEST(PlanarPnpSolver, ExactPointsGiveTheExactPose) {
  const CameraIntrinsics camera = synthetic::defaultCamera();
  const Eigen::Matrix3d r = synthetic::facingRotation(-0.6, 0.3, -0.2);
  const Eigen::Vector3d t(-0.1, 0.05, 1.5);
  const auto model = facePoints(20, 0.15, 0.12, 3);
  PlanarPnpSolver solver;
  PlanarPnpSolution solution;
  std::string reason;
  ASSERT_TRUE(solver.solve(camera, model, projectAll(camera, r, t, model, 0.0, 0), nullptr, &solution, &reason));
  EXPECT_LT((solution.pose.translation - t).norm(), 1e-6);
  EXPECT_LT(rotationAngleBetween(solution.pose.rotation, r), 1e-6);
}

// A small face far away, seen almost straight on, with noisy points: the two IPPE poses (mirror tilts
// about the line of sight) fit nearly equally well. The previous pose must decide.
TEST(PlanarPnpSolver, AmbiguityIsResolvedByThePreviousPose) {
  const CameraIntrinsics camera = synthetic::defaultCamera();
  const Eigen::Matrix3d truth = synthetic::facingRotation(0.12, 0.08, 0.0);
  const Eigen::Vector3d t(0.0, 0.0, 2.0);
  const auto model = facePoints(12, 0.03, 0.03, 5);
  const auto pixels = projectAll(camera, truth, t, model, 0.3, 6);

  PlanarPnpParams params;
  params.ambiguity_ratio = 3.0;
  PlanarPnpSolver solver(params);
  PlanarPnpSolution without_history;
  std::string reason;
  ASSERT_TRUE(solver.solve(camera, model, pixels, nullptr, &without_history, &reason)) << reason;
  ASSERT_TRUE(without_history.has_alternative);
  ASSERT_TRUE(without_history.ambiguous) << "rms " << without_history.reprojection_rms_px << " vs "
                                         << without_history.alternative_rms_px;
  EXPECT_FALSE(without_history.chosen_by_previous_pose);
  // The two candidates really differ (mirror tilts), by several degrees.
  const double separation = rotationAngleBetween(without_history.pose.rotation, without_history.alternative_rotation);
  EXPECT_GT(separation * 180.0 / M_PI, 4.0);

  // History = the truth: the solution near the truth is chosen.
  PlanarPnpSolution with_truth;
  ASSERT_TRUE(solver.solve(camera, model, pixels, &truth, &with_truth, &reason));
  EXPECT_TRUE(with_truth.chosen_by_previous_pose);
  EXPECT_LT(rotationAngleBetween(with_truth.pose.rotation, truth),
            rotationAngleBetween(with_truth.alternative_rotation, truth));
  EXPECT_LT(rotationAngleBetween(with_truth.pose.rotation, truth), 0.5 * separation);

  // History = the mirror pose: the mirror solution is chosen, so the history, not luck, decided.
  const Eigen::Vector3d normal_truth = truth.col(0);
  const Eigen::Matrix3d mirror = rotationAngleBetween(without_history.pose.rotation, truth) <
                                         rotationAngleBetween(without_history.alternative_rotation, truth)
                                     ? without_history.alternative_rotation
                                     : without_history.pose.rotation;
  PlanarPnpSolution with_mirror;
  ASSERT_TRUE(solver.solve(camera, model, pixels, &mirror, &with_mirror, &reason));
  EXPECT_LT(rotationAngleBetween(with_mirror.pose.rotation, mirror), 0.5 * separation);
  EXPECT_GT(rotationAngleBetween(with_mirror.pose.rotation, truth), 0.5 * separation);
  (void)normal_truth;
}

TEST(PlanarPnpSolver, UnambiguousCaseIgnoresAMisleadingHistory) {
  const CameraIntrinsics camera = synthetic::defaultCamera();
  const Eigen::Matrix3d truth = synthetic::facingRotation(0.5, 0.3, 0.0);
  const Eigen::Vector3d t(0.0, 0.0, 0.6);
  const auto model = facePoints(60, 0.15, 0.12, 7);
  const auto pixels = projectAll(camera, truth, t, model, 0.3, 8);
  PlanarPnpSolver solver;  // default ratio 1.5
  PlanarPnpSolution reference;
  std::string reason;
  ASSERT_TRUE(solver.solve(camera, model, pixels, nullptr, &reference, &reason));
  ASSERT_FALSE(reference.ambiguous);  // close and strongly tilted: perspective tells them apart
  const Eigen::Matrix3d wrong = reference.alternative_rotation;
  PlanarPnpSolution solution;
  ASSERT_TRUE(solver.solve(camera, model, pixels, &wrong, &solution, &reason));
  EXPECT_FALSE(solution.chosen_by_previous_pose);
  EXPECT_LT(rotationAngleBetween(solution.pose.rotation, truth) * 180.0 / M_PI, 1.0);
}

TEST(PlanarPnpSolver, TooFewPointsFailWithAReason) {
  PlanarPnpSolver solver;
  PlanarPnpSolution solution;
  std::string reason;
  const std::vector<Eigen::Vector3d> model(3, Eigen::Vector3d::Zero());
  const std::vector<Eigen::Vector2d> pixels(3, Eigen::Vector2d::Zero());
  EXPECT_FALSE(solver.solve(synthetic::defaultCamera(), model, pixels, nullptr, &solution, &reason));
  EXPECT_NE(reason.find("at least 4"), std::string::npos) << reason;
}

// The refinement against OpenCV's solvePnPRefineLM (which it replaced) from the same start, 2 deg and 2 cm
// off, on noisy points: both reach the same least-squares pose, where only the noise is left.
TEST(RefinePoseLevenbergMarquardt, ReachesTheMinimumOpenCvReaches) {
  const CameraIntrinsics camera = synthetic::defaultCamera();
  const cv::Matx33d camera_matrix(camera.fx, 0.0, camera.cx, 0.0, camera.fy, camera.cy, 0.0, 0.0, 1.0);
  for (int trial = 0; trial < 10; ++trial) {
    const Eigen::Matrix3d r = synthetic::facingRotation(0.1 * trial - 0.5, 0.05 * trial - 0.2, 0.02 * trial);
    const Eigen::Vector3d t(0.02 * trial - 0.1, 0.03, 0.5 + 0.2 * trial);
    const auto model = facePoints(40 + 20 * trial, 0.15, 0.12, 100 + trial);
    const auto pixels = projectAll(camera, r, t, model, 0.7, 200 + trial);
    Eigen::Matrix3d rotation = rotationExp(Eigen::Vector3d(0.02, -0.03, 0.01).normalized() * (2.0 * M_PI / 180.0)) * r;
    Eigen::Vector3d translation = t + Eigen::Vector3d(0.02, -0.01, 0.015).normalized() * 0.02;

    std::vector<cv::Point3d> object;
    std::vector<cv::Point2d> image;
    for (size_t i = 0; i < model.size(); ++i) {
      object.emplace_back(model[i].x(), model[i].y(), model[i].z());
      image.emplace_back(pixels[i].x(), pixels[i].y());
    }
    const Eigen::Vector3d start_vector = rotationLog(rotation);
    cv::Mat rvec = (cv::Mat_<double>(3, 1) << start_vector.x(), start_vector.y(), start_vector.z());
    cv::Mat tvec = (cv::Mat_<double>(3, 1) << translation.x(), translation.y(), translation.z());
    cv::solvePnPRefineLM(object, image, camera_matrix, cv::noArray(), rvec, tvec,
                         cv::TermCriteria(cv::TermCriteria::EPS + cv::TermCriteria::COUNT, 20, 1e-10));
    const Eigen::Matrix3d opencv_rotation = rotationExp(Eigen::Vector3d(rvec.at<double>(0), rvec.at<double>(1), rvec.at<double>(2)));
    const Eigen::Vector3d opencv_translation(tvec.at<double>(0), tvec.at<double>(1), tvec.at<double>(2));

    const double start_rms = reprojectionRms(camera, rotation, translation, model, pixels);
    const int iterations = refinePoseLevenbergMarquardt(camera, model, pixels, 20, &rotation, &translation);
    EXPECT_GT(iterations, 0);
    const double final_rms = reprojectionRms(camera, rotation, translation, model, pixels);
    EXPECT_LT(final_rms, start_rms) << "trial " << trial;
    EXPECT_NEAR(final_rms, 0.7 * std::sqrt(2.0), 0.2) << "trial " << trial;  // the noise is what is left
    EXPECT_LT((translation - opencv_translation).norm(), 1e-7) << "trial " << trial;
    EXPECT_LT(rotationAngleBetween(rotation, opencv_rotation), 1e-7) << "trial " << trial;
  }
}

// A start with a point behind the camera is left as it was: no step is taken from an undefined cost.
TEST(RefinePoseLevenbergMarquardt, LeavesAStartBehindTheCameraAlone) {
  const CameraIntrinsics camera = synthetic::defaultCamera();
  const auto model = facePoints(20, 0.15, 0.12, 7);
  const auto pixels = projectAll(camera, synthetic::facingRotation(0.0, 0.0, 0.0), Eigen::Vector3d(0, 0, 1), model, 0.0, 8);
  Eigen::Matrix3d rotation = synthetic::facingRotation(0.0, 0.0, 0.0);
  Eigen::Vector3d translation(0.0, 0.0, -1.0);
  EXPECT_EQ(refinePoseLevenbergMarquardt(camera, model, pixels, 20, &rotation, &translation), 0);
  EXPECT_EQ(translation, Eigen::Vector3d(0.0, 0.0, -1.0));
}
