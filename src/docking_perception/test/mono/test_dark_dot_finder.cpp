// DarkDotFinder: the printed dots found anywhere in an image, with no prior (the visible cold search).
#include <gtest/gtest.h>

#include <cmath>
#include <opencv2/core.hpp>
#include <opencv2/imgproc.hpp>
#include <vector>

#include "docking_perception/mono/dark_dot_locator.h"

using docking_perception::mono::DarkDotFinder;
using docking_perception::mono::LedBlob;

namespace {

// A mid-grey print with dark squares and bars (the print's own dark details), and dark dots of `radius` px,
// each on a white ring of 1.8 radii, blurred by `blur_sigma` px.
cv::Mat printWithDots(const std::vector<cv::Point2d>& dots, double radius, double blur_sigma) {
  cv::Mat image(480, 640, CV_8UC1, cv::Scalar(140));
  cv::rectangle(image, cv::Rect(40, 40, 30, 20), cv::Scalar(30), cv::FILLED);
  cv::rectangle(image, cv::Rect(500, 380, 12, 60), cv::Scalar(20), cv::FILLED);
  cv::line(image, cv::Point(100, 400), cv::Point(300, 430), cv::Scalar(25), 3);
  constexpr int kShift = 4;  // sub-pixel drawing: 1/16 px
  for (const cv::Point2d& d : dots) {
    const cv::Point centre(static_cast<int>(d.x * 16.0), static_cast<int>(d.y * 16.0));
    cv::circle(image, centre, static_cast<int>(1.8 * radius * 16.0), cv::Scalar(235), cv::FILLED, cv::LINE_AA, kShift);
    cv::circle(image, centre, static_cast<int>(radius * 16.0), cv::Scalar(25), cv::FILLED, cv::LINE_AA, kShift);
  }
  if (blur_sigma > 0.0) cv::GaussianBlur(image, image, cv::Size(0, 0), blur_sigma);
  return image;
}

double nearest(const std::vector<LedBlob>& found, const cv::Point2d& p) {
  double best = 1e9;
  for (const LedBlob& b : found) best = std::min(best, std::hypot(b.centroid.x() - p.x, b.centroid.y() - p.y));
  return best;
}

}  // namespace

TEST(DarkDotFinder, FindsEveryDotAtItsRadiusUnderBlur) {
  const std::vector<cv::Point2d> dots = {{120.3, 150.6}, {250.8, 310.2}, {420.4, 90.9}, {560.5, 260.1}, {330.2, 200.7}};
  const std::vector<double> radii = {2.1, 3.0, 4.2, 6.0, 8.5};
  const DarkDotFinder finder(radii);
  for (const double blur : {0.0, 2.0}) {
    const std::vector<std::vector<LedBlob>> found = finder.find(printWithDots(dots, 4.2, blur), 16);
    ASSERT_EQ(found.size(), radii.size());
    for (const cv::Point2d& d : dots) EXPECT_LT(nearest(found[2], d), 0.5) << "blur " << blur << " dot " << d;
  }
}

TEST(DarkDotFinder, AFlatOrGradedImageHasNoDots) {
  const DarkDotFinder finder({2.1, 4.2, 8.5});
  cv::Mat flat(240, 320, CV_8UC1, cv::Scalar(128));
  for (const auto& level : finder.find(flat, 16)) EXPECT_TRUE(level.empty());
  cv::Mat graded(240, 320, CV_8UC1);
  for (int y = 0; y < graded.rows; ++y) graded.row(y).setTo(cv::Scalar(40 + y * 180 / graded.rows));
  for (const auto& level : finder.find(graded, 16)) EXPECT_TRUE(level.empty());
}
