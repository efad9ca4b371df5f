#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <iostream>
#include <vector>

#include <opencv2/core.hpp>
#include <opencv2/imgproc.hpp>

#include "docking_perception/mono/upright_descriptor.h"

using docking_perception::mono::UprightRingDescriptor;

namespace {

// Smooth random texture (blobs a few pixels across, like a print seen at a distance), values lo..hi.
cv::Mat texture(int size, int lo, int hi, uint64_t seed) {
  cv::Mat noise(size, size, CV_32F);
  cv::RNG rng(seed);
  rng.fill(noise, cv::RNG::UNIFORM, 0.0, 1.0);
  cv::GaussianBlur(noise, noise, cv::Size(0, 0), 1.5);
  cv::normalize(noise, noise, lo, hi, cv::NORM_MINMAX);
  cv::Mat gray;
  noise.convertTo(gray, CV_8U);
  return gray;
}

int hamming(const cv::Mat& a, int row_a, const cv::Mat& b, int row_b) {
  return static_cast<int>(cv::norm(a.row(row_a), b.row(row_b), cv::NORM_HAMMING));
}

double median(std::vector<int> values) {
  std::nth_element(values.begin(), values.begin() + static_cast<long>(values.size() / 2), values.end());
  return values[values.size() / 2];
}

std::vector<cv::KeyPoint> gridKeypoints(int size, int margin, int spacing) {
  std::vector<cv::KeyPoint> keypoints;
  for (int y = margin; y < size - margin; y += spacing) {
    for (int x = margin; x < size - margin; x += spacing) keypoints.emplace_back(static_cast<float>(x), static_cast<float>(y), 7.f);
  }
  return keypoints;
}

}  // namespace

// Keypoints whose samples would leave the image are dropped (rows stay aligned with the keypoints
// kept), and a keypoint is described by its pixels only: the same pixels in a sub-image view (another
// row step) give the same bits.
TEST(UprightRingDescriptor, DropsKeypointsAtTheBorderAndDescribesViewsByTheirPixels) {
  const UprightRingDescriptor descriptor;
  const int border = descriptor.borderPx();
  ASSERT_GT(border, 8);
  const cv::Mat image = texture(120, 0, 255, 3);
  std::vector<cv::KeyPoint> keypoints = {cv::KeyPoint(border - 1.f, 60.f, 7.f), cv::KeyPoint(border, 60.f, 7.f),
                                         cv::KeyPoint(60.f, 119.f - border, 7.f), cv::KeyPoint(60.f, 120.f - border, 7.f),
                                         cv::KeyPoint(50.f, 45.f, 7.f)};
  cv::Mat full;
  descriptor.compute(image, &keypoints, &full);
  ASSERT_EQ(keypoints.size(), 3u);
  ASSERT_EQ(full.rows, 3);
  EXPECT_EQ(full.cols, UprightRingDescriptor::kBytes);
  EXPECT_FLOAT_EQ(keypoints[0].pt.x, static_cast<float>(border));
  EXPECT_FLOAT_EQ(keypoints[1].pt.y, 119.f - border);

  const cv::Rect region(20, 15, 70, 80);
  std::vector<cv::KeyPoint> in_view = {cv::KeyPoint(50.f - region.x, 45.f - region.y, 7.f)};
  cv::Mat from_view;
  descriptor.compute(image(region), &in_view, &from_view);
  ASSERT_EQ(from_view.rows, 1);
  EXPECT_EQ(hamming(full, 2, from_view, 0), 0);
  // And the bits depend on the place: another keypoint differs in about half of them.
  std::vector<cv::KeyPoint> elsewhere = {cv::KeyPoint(70.f, 70.f, 7.f)};
  cv::Mat other;
  descriptor.compute(image, &elsewhere, &other);
  EXPECT_GT(hamming(full, 2, other, 0), UprightRingDescriptor::kBits / 4);
}

// Only the order of the smoothed intensities counts: gain and offset (exposure) change no bit.
TEST(UprightRingDescriptor, IsUnchangedByGainAndOffset) {
  const UprightRingDescriptor descriptor;
  const cv::Mat dim = texture(100, 0, 120, 5);
  cv::Mat bright;
  dim.convertTo(bright, CV_8U, 2.0, 10.0);  // exact: 2 x 120 + 10 < 256
  std::vector<cv::KeyPoint> keypoints = gridKeypoints(100, 15, 10);
  std::vector<cv::KeyPoint> same = keypoints;
  cv::Mat a, b;
  descriptor.compute(dim, &keypoints, &a);
  descriptor.compute(bright, &same, &b);
  ASSERT_EQ(a.rows, b.rows);
  ASSERT_GT(a.rows, 20);
  EXPECT_EQ(cv::norm(a, b, cv::NORM_HAMMING), 0.0);
}

// No orientation: a few degrees of roll (the test bed's level cameras) keep a point's descriptor much
// nearer its own than any other point's; a quarter turn does not (the reason for upright_descriptors
// false on a camera that rolls).
TEST(UprightRingDescriptor, ToleratesSmallRollButNotAQuarterTurn) {
  const UprightRingDescriptor descriptor;
  const int size = 200;
  const cv::Mat image = texture(size, 0, 255, 7);
  const cv::Point2f centre(0.5f * (size - 1), 0.5f * (size - 1));
  auto turned = [&](double degrees, std::vector<cv::KeyPoint>* keypoints) {
    const cv::Mat rotation = cv::getRotationMatrix2D(centre, degrees, 1.0);
    cv::Mat out;
    cv::warpAffine(image, out, rotation, image.size(), cv::INTER_LINEAR, cv::BORDER_REFLECT);
    const cv::Matx23d r(rotation);
    for (cv::KeyPoint& kp : *keypoints) {
      kp.pt = cv::Point2f(static_cast<float>(r(0, 0) * kp.pt.x + r(0, 1) * kp.pt.y + r(0, 2)),
                          static_cast<float>(r(1, 0) * kp.pt.x + r(1, 1) * kp.pt.y + r(1, 2)));
    }
    return out;
  };
  std::vector<cv::KeyPoint> keypoints = gridKeypoints(size, 60, 16);
  cv::Mat upright;
  descriptor.compute(image, &keypoints, &upright);
  ASSERT_GE(upright.rows, 25);
  std::vector<int> to_others;
  for (int i = 0; i < upright.rows; ++i) {
    for (int j = i + 1; j < upright.rows; ++j) to_others.push_back(hamming(upright, i, upright, j));
  }
  const double other_median = median(to_others);
  for (const double degrees : {5.0, 90.0}) {
    std::vector<cv::KeyPoint> moved = keypoints;
    const cv::Mat rolled_image = turned(degrees, &moved);
    cv::Mat rolled;
    descriptor.compute(rolled_image, &moved, &rolled);
    ASSERT_EQ(rolled.rows, upright.rows) << degrees;
    std::vector<int> to_self;
    for (int i = 0; i < upright.rows; ++i) to_self.push_back(hamming(upright, i, rolled, i));
    std::cout << degrees << " deg: own " << median(to_self) << ", others " << other_median << "\n";
    if (degrees < 10.0) {
      EXPECT_LT(median(to_self), 0.4 * other_median) << degrees << " deg";
    } else {
      EXPECT_GT(median(to_self), 0.7 * other_median) << degrees << " deg";
    }
  }
}
