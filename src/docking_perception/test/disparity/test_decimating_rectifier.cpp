// The far stage's rectification at a reduced resolution (DecimatingRectifier): where a known ray lands
// in the output, against image_geometry's reduced camera (the projection's pixel rows / decimation), on a
// distorted camera; input checks; the detector's pixel settings at a decimation.
#include <cmath>
#include <stdexcept>
#include <vector>

#include <gtest/gtest.h>
#include <opencv2/calib3d.hpp>
#include <opencv2/imgproc.hpp>

#include "docking_perception/disparity/decimating_rectifier.h"
#include "synthetic_stereo.h"

namespace docking_perception {
namespace disparity {
namespace {

// The raw image of small bright discs whose rays are `rays` (rectified frame), on a dark background.
cv::Mat rawImageOfDiscs(const PinholeCalibration& c, const std::vector<cv::Point3d>& rays) {
  // Rectified frame -> camera frame: x_cam = R^T x_rect.
  std::vector<cv::Point3d> camera_points;
  for (const auto& ray : rays) {
    const cv::Vec3d p = c.rectification.t() * cv::Vec3d(ray.x, ray.y, ray.z);
    camera_points.emplace_back(p[0], p[1], p[2]);
  }
  std::vector<cv::Point2d> pixels;
  cv::projectPoints(camera_points, cv::Vec3d(0, 0, 0), cv::Vec3d(0, 0, 0), cv::Mat(c.camera_matrix),
                    cv::Mat(c.distortion), pixels);
  // Supersampled by 8 so each disc's centroid is where it was drawn, to a few hundredths of a pixel.
  constexpr int kSuper = 8;
  cv::Mat big(c.size.height * kSuper, c.size.width * kSuper, CV_8UC1, cv::Scalar(10));
  for (const auto& p : pixels) {
    cv::circle(big, cv::Point(static_cast<int>(std::lround((p.x + 0.5) * kSuper * 16.0 - 0.5 * 16.0)),
                              static_cast<int>(std::lround((p.y + 0.5) * kSuper * 16.0 - 0.5 * 16.0))),
               6 * kSuper * 16, cv::Scalar(240), cv::FILLED, cv::LINE_AA, 4);
  }
  cv::Mat raw;
  cv::resize(big, raw, c.size, 0.0, 0.0, cv::INTER_AREA);
  return raw;
}

// Intensity-weighted centroid of the disc nearest `guess` in `image` (background subtracted).
cv::Point2d centroidNear(const cv::Mat& image, cv::Point2d guess, int radius) {
  double sum = 0.0, su = 0.0, sv = 0.0;
  for (int v = static_cast<int>(guess.y) - radius; v <= static_cast<int>(guess.y) + radius; ++v) {
    for (int u = static_cast<int>(guess.x) - radius; u <= static_cast<int>(guess.x) + radius; ++u) {
      if (u < 0 || v < 0 || u >= image.cols || v >= image.rows) continue;
      const double w = std::max(0.0, image.at<std::uint8_t>(v, u) - 10.0);
      sum += w;
      su += w * u;
      sv += w * v;
    }
  }
  return sum > 0.0 ? cv::Point2d(su / sum, sv / sum) : cv::Point2d(-1.0, -1.0);
}

TEST(DecimatingRectifier, PutsEachRayWhereTheReducedProjectionSays) {
  const PinholeCalibration camera = testing::distortedWebcam();
  const std::vector<cv::Point3d> rays = {{0.0, 0.0, 1.0}, {-0.4, -0.3, 1.0}, {0.45, 0.28, 1.0}, {0.3, -0.32, 1.0}};
  const cv::Mat raw = rawImageOfDiscs(camera, rays);
  for (int factor : {1, 2}) {
    const DecimatingRectifier rectifier(camera, factor);
    ASSERT_EQ(rectifier.outputSize(), cv::Size(640 / factor, 480 / factor));
    cv::Mat rectified;
    rectifier.rectify(raw, &rectified);
    ASSERT_EQ(rectified.size(), rectifier.outputSize());
    const cv::Matx34d p = rectifier.outputProjection();
    EXPECT_DOUBLE_EQ(p(0, 0), 550.0 / factor);
    EXPECT_DOUBLE_EQ(p(0, 2), 318.0 / factor);
    for (const auto& ray : rays) {
      const cv::Point2d expected(p(0, 0) * ray.x / ray.z + p(0, 2), p(1, 1) * ray.y / ray.z + p(1, 2));
      const cv::Point2d found = centroidNear(rectified, expected, 12 / factor + 2);
      EXPECT_NEAR(found.x, expected.x, 0.15) << "factor " << factor << " ray " << ray;
      EXPECT_NEAR(found.y, expected.y, 0.15) << "factor " << factor << " ray " << ray;
    }
  }
}

TEST(DecimatingRectifier, AveragesInsteadOfSampling) {
  // A one-pixel checkerboard averages to mid grey at half resolution; sampling every second pixel
  // would give all black or all white.
  PinholeCalibration camera;
  camera.size = cv::Size(64, 48);
  camera.camera_matrix = cv::Matx33d(50.0, 0.0, 31.5, 0.0, 50.0, 23.5, 0.0, 0.0, 1.0);
  camera.rectification = cv::Matx33d::eye();
  camera.projection = cv::Matx34d(50.0, 0.0, 31.5, 0.0, 0.0, 50.0, 23.5, 0.0, 0.0, 0.0, 1.0, 0.0);
  cv::Mat checker(camera.size, CV_8UC1);
  for (int v = 0; v < checker.rows; ++v) {
    for (int u = 0; u < checker.cols; ++u) checker.at<std::uint8_t>(v, u) = ((u + v) % 2) ? 200 : 0;
  }
  cv::Mat rectified;
  DecimatingRectifier(camera, 2).rectify(checker, &rectified);
  const cv::Mat inner = rectified(cv::Rect(4, 4, rectified.cols - 8, rectified.rows - 8));
  double low = 0.0, high = 0.0;
  cv::minMaxLoc(inner, &low, &high);
  EXPECT_GE(low, 90.0);
  EXPECT_LE(high, 110.0);
}

TEST(DecimatingRectifier, RefusesWhatItCannotRectify) {
  PinholeCalibration camera = testing::distortedWebcam();
  EXPECT_TRUE(validateDecimation(camera, 2).empty());
  EXPECT_FALSE(validateDecimation(camera, 0).empty());
  EXPECT_FALSE(validateDecimation(camera, 5).empty());
  EXPECT_FALSE(validateDecimation(camera, 3).empty());  // 640 / 3 is not whole
  PinholeCalibration uncalibrated = camera;
  uncalibrated.projection = cv::Matx34d::zeros();
  EXPECT_FALSE(validateDecimation(uncalibrated, 2).empty());
  EXPECT_THROW(DecimatingRectifier(uncalibrated, 2), std::invalid_argument);
  PinholeCalibration odd_distortion = camera;
  odd_distortion.distortion = {0.1, 0.2, 0.3};
  EXPECT_FALSE(validateDecimation(odd_distortion, 2).empty());

  const DecimatingRectifier rectifier(camera, 2);
  cv::Mat out;
  EXPECT_THROW(rectifier.rectify(cv::Mat(480, 640, CV_8UC3, cv::Scalar::all(0)), &out), std::invalid_argument);
  EXPECT_THROW(rectifier.rectify(cv::Mat(240, 320, CV_8UC1, cv::Scalar(0)), &out), std::invalid_argument);
  EXPECT_THROW(rectifier.rectify(cv::Mat(), &out), std::invalid_argument);
}

TEST(DetectorParamsAtDecimation, ScalesLengthsAndAreasAndTakesTheReducedBlobLimits) {
  DetectorParams full;  // the values these scalings are checked on (the shipped ones)
  full.closest_min_pixels = 150;
  full.min_blob_area_px = 400;
  full.min_blob_thickness_px = 16.0;
  full.reduced_min_blob_area_px = 600;
  full.reduced_min_blob_thickness_px = 20.0;
  full.max_disparity_px = 92.0;
  full.disparity_sigma_px = 0.25;
  full.shape_tolerance_px = 8.0;
  full.border_margin_px = 2;
  full.target_depth_m = 0.5;
  full.footprint_fit_enabled = true;
  const DetectorParams same = detectorParamsAtDecimation(full, 1);
  EXPECT_EQ(same.min_blob_area_px, 400);
  EXPECT_TRUE(same.footprint_fit_enabled);
  EXPECT_DOUBLE_EQ(same.min_blob_thickness_px, 16.0);
  const DetectorParams half = detectorParamsAtDecimation(full, 2);
  EXPECT_EQ(half.closest_min_pixels, 38);
  EXPECT_EQ(half.min_blob_area_px, 150);
  EXPECT_DOUBLE_EQ(half.min_blob_thickness_px, 10.0);
  EXPECT_DOUBLE_EQ(half.max_disparity_px, 46.0);
  EXPECT_DOUBLE_EQ(half.disparity_sigma_px, 0.125);
  EXPECT_DOUBLE_EQ(half.shape_tolerance_px, 4.0);
  EXPECT_EQ(half.border_margin_px, 1);
  EXPECT_DOUBLE_EQ(half.target_depth_m, 0.5);  // metres stay metres
  EXPECT_FALSE(half.footprint_fit_enabled);     // too coarse a depth for it (far_tracking_still_3m)
  EXPECT_NO_THROW(validate(half, TargetShape()));
}

}  // namespace
}  // namespace disparity
}  // namespace docking_perception
