#include <gtest/gtest.h>

#include <opencv2/core.hpp>
#include <opencv2/imgproc.hpp>
#include <vector>

#include "docking_perception/mono/led_pattern_detector.h"
#include "synthetic_scene.h"

using namespace docking_perception::mono;  // NOLINT: test file

namespace {

std::vector<Eigen::Vector3d> ledsInCamera(const Eigen::Matrix3d& r, const Eigen::Vector3d& t) {
  std::vector<Eigen::Vector3d> points;
  for (const auto& m : synthetic::defaultMarkers()) points.push_back(r * m + t);
  return points;
}

std::vector<LedBlob> blobsAt(const std::vector<Eigen::Vector2d>& pixels) {
  std::vector<LedBlob> blobs;
  for (const auto& p : pixels) {
    LedBlob blob;
    blob.centroid = p;
    blob.area_px = 10.0;
    blobs.push_back(blob);
  }
  return blobs;
}

MarkerPixels projected(const CameraIntrinsics& camera, const Eigen::Matrix3d& r, const Eigen::Vector3d& t) {
  MarkerPixels pixels;
  const auto points = ledsInCamera(r, t);
  for (int i = 0; i < kMarkerCount; ++i) pixels[i] = camera.project(points[i]);
  return pixels;
}

}  // namespace

TEST(LedPatternDetector, BlobCentroidsAreSubPixel) {
  const CameraIntrinsics camera = synthetic::defaultCamera();
  cv::Mat image(480, 640, CV_8UC1, cv::Scalar(15));
  const std::vector<Eigen::Vector2d> centres = {{100.3, 200.7}, {400.55, 50.25}, {320.9, 400.1}};
  for (const auto& c : centres) synthetic::drawSpot(&image, c, 1.8, 300.0);
  LedPatternDetector detector(synthetic::defaultMarkers());
  const auto blobs = detector.detectBlobs(image);
  ASSERT_EQ(blobs.size(), centres.size());
  for (const auto& c : centres) {
    double best = 1e9;
    for (const auto& b : blobs) best = std::min(best, (b.centroid - c).norm());
    EXPECT_LT(best, 0.1) << c.transpose();
  }
  (void)camera;
}

TEST(LedPatternDetector, IdentifiesThePatternInManyPoses) {
  const CameraIntrinsics camera = synthetic::defaultCamera();
  LedPatternDetector detector(synthetic::defaultMarkers());
  struct Pose {
    double yaw, pitch, roll;
    Eigen::Vector3d t;
  };
  // Includes yaw 55 deg, where arm A (0.22 m, horizontal) looks shorter than arm B (0.16 m), and rolls
  // of 90 and 180 deg: only the handedness can tell the arms apart there.
  const std::vector<Pose> poses = {{0.0, 0.0, 0.0, {0.0, 0.0, 1.0}},      {0.96, 0.0, 0.0, {0.05, 0.0, 0.8}},
                                   {0.0, 0.0, M_PI / 2, {0.0, 0.0, 1.0}}, {0.0, 0.0, M_PI, {0.0, 0.0, 1.0}},
                                   {-0.6, 0.4, 0.3, {-0.1, 0.05, 0.5}},   {0.3, -0.3, -2.0, {0.1, -0.1, 2.0}}};
  for (const Pose& pose : poses) {
    const MarkerPixels truth = projected(camera, synthetic::facingRotation(pose.yaw, pose.pitch, pose.roll), pose.t);
    // Shuffle the order the blobs come in.
    const std::vector<int> order = {3, 0, 4, 2, 1};
    std::vector<Eigen::Vector2d> pixels;
    for (int i : order) pixels.push_back(truth[i]);
    std::string reason;
    const auto candidates = detector.identifyPattern(blobsAt(pixels), &reason);
    ASSERT_FALSE(candidates.empty()) << reason << " yaw " << pose.yaw << " roll " << pose.roll;
    for (int i = 0; i < kMarkerCount; ++i) {
      EXPECT_LT((candidates.front().pixels[i] - truth[i]).norm(), 1e-9)
          << "marker " << i << " yaw " << pose.yaw << " roll " << pose.roll;
    }
  }
}

TEST(LedPatternDetector, MissingBlobFailsCleanlyWithAReason) {
  const CameraIntrinsics camera = synthetic::defaultCamera();
  LedPatternDetector detector(synthetic::defaultMarkers());
  const MarkerPixels truth = projected(camera, synthetic::facingRotation(0.2), Eigen::Vector3d(0.0, 0.0, 1.0));
  for (int missing = 0; missing < kMarkerCount; ++missing) {
    std::vector<Eigen::Vector2d> pixels;
    for (int i = 0; i < kMarkerCount; ++i) {
      if (i != missing) pixels.push_back(truth[i]);
    }
    std::string reason;
    EXPECT_TRUE(detector.identifyPattern(blobsAt(pixels), &reason).empty());
    EXPECT_NE(reason.find("found 4 LED blobs"), std::string::npos) << reason;
  }
  // Four LEDs plus one unrelated blob: five blobs, still no pattern, and a different reason.
  std::vector<Eigen::Vector2d> pixels(truth.begin(), truth.begin() + 4);
  pixels.emplace_back(600.0, 50.0);
  std::string reason;
  EXPECT_TRUE(detector.identifyPattern(blobsAt(pixels), &reason).empty());
  EXPECT_NE(reason.find("no 5-point LED pattern"), std::string::npos) << reason;
}

TEST(LedPatternDetector, ExtraBlobsDoNotPreventIdentification) {
  const CameraIntrinsics camera = synthetic::defaultCamera();
  LedPatternDetector detector(synthetic::defaultMarkers());
  const MarkerPixels truth = projected(camera, synthetic::facingRotation(-0.3, 0.1), Eigen::Vector3d(0.02, 0.0, 0.9));
  // A random reflection, and a nasty one on the extension of arm A that forms a collinear triple with
  // markers 1 and 0 (0 at its middle).
  const std::vector<Eigen::Vector2d> extras = {{50.0, 430.0}, truth[0] + (truth[0] - truth[1])};
  for (const auto& extra : extras) {
    std::vector<Eigen::Vector2d> pixels(truth.begin(), truth.end());
    pixels.insert(pixels.begin() + 2, extra);
    std::string reason;
    const auto candidates = detector.identifyPattern(blobsAt(pixels), &reason);
    ASSERT_FALSE(candidates.empty()) << reason;
    for (int i = 0; i < kMarkerCount; ++i) EXPECT_LT((candidates.front().pixels[i] - truth[i]).norm(), 1e-9);
  }
}

TEST(LedPatternDetector, RenderedIrImageEndToEnd) {
  const CameraIntrinsics camera = synthetic::defaultCamera();
  const Eigen::Matrix3d r = synthetic::facingRotation(0.4, 0.0, 0.1);
  const Eigen::Vector3d t(0.05, 0.02, 1.2);
  auto points = ledsInCamera(r, t);
  points.push_back(Eigen::Vector3d(-0.3, 0.2, 1.5));  // an extra light source
  const cv::Mat image = synthetic::renderLedSpots(camera, points, 0.005, 21);
  LedPatternDetector detector(synthetic::defaultMarkers());
  const auto blobs = detector.detectBlobs(image);
  EXPECT_EQ(blobs.size(), 6u);
  std::string reason;
  const auto candidates = detector.identifyPattern(blobs, &reason);
  ASSERT_FALSE(candidates.empty()) << reason;
  const MarkerPixels truth = projected(camera, r, t);
  for (int i = 0; i < kMarkerCount; ++i) EXPECT_LT((candidates.front().pixels[i] - truth[i]).norm(), 0.15);
}
