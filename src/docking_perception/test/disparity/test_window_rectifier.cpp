// The far stage's rectification (WindowRectifier): where a known ray lands in the output, against the
// projection P, on a distorted camera; input checks.
#include <cmath>
#include <stdexcept>
#include <vector>

#include <gtest/gtest.h>
#include <opencv2/calib3d.hpp>
#include <opencv2/imgproc.hpp>

#include "docking_perception/disparity/window_rectifier.h"
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

TEST(WindowRectifier, PutsEachRayWhereTheProjectionSays) {
  const PinholeCalibration camera = testing::distortedWebcam();
  const std::vector<cv::Point3d> rays = {{0.0, 0.0, 1.0}, {-0.4, -0.3, 1.0}, {0.45, 0.28, 1.0}, {0.3, -0.32, 1.0}};
  const cv::Mat raw = rawImageOfDiscs(camera, rays);
  const WindowRectifier rectifier(camera);
  ASSERT_EQ(rectifier.outputSize(), cv::Size(640, 480));
  cv::Mat rectified;
  rectifier.rectify(raw, &rectified);
  ASSERT_EQ(rectified.size(), rectifier.outputSize());
  const cv::Matx34d p = rectifier.outputProjection();
  EXPECT_DOUBLE_EQ(p(0, 0), 550.0);
  EXPECT_DOUBLE_EQ(p(0, 2), 318.0);
  for (const auto& ray : rays) {
    const cv::Point2d expected(p(0, 0) * ray.x / ray.z + p(0, 2), p(1, 1) * ray.y / ray.z + p(1, 2));
    const cv::Point2d found = centroidNear(rectified, expected, 14);
    EXPECT_NEAR(found.x, expected.x, 0.15) << "ray " << ray;
    EXPECT_NEAR(found.y, expected.y, 0.15) << "ray " << ray;
  }
}

TEST(WindowRectifier, RefusesWhatItCannotRectify) {
  PinholeCalibration camera = testing::distortedWebcam();
  EXPECT_TRUE(validateCalibration(camera).empty());
  PinholeCalibration uncalibrated = camera;
  uncalibrated.projection = cv::Matx34d::zeros();
  EXPECT_FALSE(validateCalibration(uncalibrated).empty());
  EXPECT_THROW(WindowRectifier{uncalibrated}, std::invalid_argument);
  PinholeCalibration odd_distortion = camera;
  odd_distortion.distortion = {0.1, 0.2, 0.3};
  EXPECT_FALSE(validateCalibration(odd_distortion).empty());

  const WindowRectifier rectifier(camera);
  cv::Mat out;
  EXPECT_THROW(rectifier.rectify(cv::Mat(480, 640, CV_8UC3, cv::Scalar::all(0)), &out), std::invalid_argument);
  EXPECT_THROW(rectifier.rectify(cv::Mat(240, 320, CV_8UC1, cv::Scalar(0)), &out), std::invalid_argument);
  EXPECT_THROW(rectifier.rectify(cv::Mat(), &out), std::invalid_argument);
  EXPECT_THROW(rectifier.rectifyWindow(cv::Mat(480, 640, CV_8UC1, cv::Scalar(0)), cv::Rect(600, 0, 100, 10), &out),
               std::invalid_argument);
}

}  // namespace
}  // namespace disparity
}  // namespace docking_perception
