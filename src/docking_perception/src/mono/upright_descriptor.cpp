#include "docking_perception/mono/upright_descriptor.h"

#include <algorithm>
#include <cmath>
#include <tuple>

namespace docking_perception {
namespace mono {
namespace {

// The rings: radius (px), samples, smoothing box half-size. The box's sigma ((2h+1)/sqrt(12): 0.87 px
// for 3x3, 1.44 px for 5x5) follows the spacing of the ring's samples (radius x sin(pi / samples): 0.8,
// 0.9, 1.3, 1.4 px), as BRISK's Gaussian does, so every pixel of the disc counts and none twice.
struct Ring {
  double radius_px;
  int samples;
  int half_box;
};
constexpr Ring kRings[] = {{0.0, 1, 1}, {2.5, 10, 1}, {4.2, 14, 1}, {6.3, 15, 2}, {9.2, 20, 2}};
// Every box's sum is scaled to this area (the least common multiple of 9 and 25) to compare exactly.
constexpr int32_t kCommonBoxArea = 225;

}  // namespace

UprightRingDescriptor::UprightRingDescriptor() {
  int n = 0;
  for (size_t r = 0; r < sizeof(kRings) / sizeof(kRings[0]); ++r) {
    const Ring& ring = kRings[r];
    // Odd rings turned by half a step: neighbouring rings' samples interleave instead of lining up.
    const double offset = (r % 2 == 1) ? M_PI / ring.samples : 0.0;
    for (int k = 0; k < ring.samples; ++k, ++n) {
      const double angle = offset + 2.0 * M_PI * k / ring.samples;
      Sample& s = samples_[static_cast<size_t>(n)];
      s.dx = static_cast<int>(std::lround(ring.radius_px * std::cos(angle)));
      s.dy = static_cast<int>(std::lround(ring.radius_px * std::sin(angle)));
      s.half_box = ring.half_box;
      const int side = 2 * ring.half_box + 1;
      area_scale_[static_cast<size_t>(n)] = kCommonBoxArea / (side * side);
      border_px_ = std::max({border_px_, std::abs(s.dx) + s.half_box, std::abs(s.dy) + s.half_box});
    }
  }
  // The 512 shortest pairs (ties in index order): the nearest comparisons are the least affected by
  // perspective and by the few degrees of roll the descriptor does not undo.
  std::vector<std::tuple<int, int, int>> candidates;  // squared distance, first, second
  for (int i = 0; i < kSamples; ++i) {
    for (int j = i + 1; j < kSamples; ++j) {
      const int ddx = samples_[static_cast<size_t>(i)].dx - samples_[static_cast<size_t>(j)].dx;
      const int ddy = samples_[static_cast<size_t>(i)].dy - samples_[static_cast<size_t>(j)].dy;
      candidates.emplace_back(ddx * ddx + ddy * ddy, i, j);
    }
  }
  std::sort(candidates.begin(), candidates.end());
  for (int b = 0; b < kBits; ++b) {
    pairs_[static_cast<size_t>(b)] = {static_cast<uint8_t>(std::get<1>(candidates[static_cast<size_t>(b)])),
                                      static_cast<uint8_t>(std::get<2>(candidates[static_cast<size_t>(b)]))};
  }
}

void UprightRingDescriptor::sampleRing(const cv::Mat& gray, int x, int y, int32_t* values) const {
  const size_t step = gray.step[0];
  for (int n = 0; n < kSamples; ++n) {
    const Sample& s = samples_[static_cast<size_t>(n)];
    const int h = s.half_box;
    const uint8_t* row = gray.ptr<uint8_t>(y + s.dy - h) + (x + s.dx - h);
    int32_t sum = 0;
    // The two box sizes as separate loops of a compiled-in length, which the compiler unrolls.
    if (h == 1) {
      for (int r = 0; r < 3; ++r, row += step) sum += row[0] + row[1] + row[2];
    } else {
      for (int r = 0; r < 5; ++r, row += step) sum += row[0] + row[1] + row[2] + row[3] + row[4];
    }
    values[n] = sum * area_scale_[static_cast<size_t>(n)];
  }
}

void UprightRingDescriptor::compute(const cv::Mat& gray, std::vector<cv::KeyPoint>* keypoints,
                                    cv::Mat* descriptors) const {
  CV_Assert(gray.type() == CV_8UC1);
  // Keep the keypoints whose samples lie inside the image (pixel centres at integers).
  const auto outside = [&](const cv::KeyPoint& kp) {
    const long x = std::lround(kp.pt.x);
    const long y = std::lround(kp.pt.y);
    return x < border_px_ || y < border_px_ || x >= gray.cols - border_px_ || y >= gray.rows - border_px_;
  };
  keypoints->erase(std::remove_if(keypoints->begin(), keypoints->end(), outside), keypoints->end());
  descriptors->create(static_cast<int>(keypoints->size()), kBytes, CV_8UC1);
  int32_t values[kSamples];
  for (size_t k = 0; k < keypoints->size(); ++k) {
    const cv::Point2f& pt = (*keypoints)[k].pt;
    sampleRing(gray, static_cast<int>(std::lround(pt.x)), static_cast<int>(std::lround(pt.y)), values);
    uint8_t* out = descriptors->ptr<uint8_t>(static_cast<int>(k));
    for (int byte = 0; byte < kBytes; ++byte) {
      unsigned bits = 0;
      for (int bit = 0; bit < 8; ++bit) {
        const std::pair<uint8_t, uint8_t>& pair = pairs_[static_cast<size_t>(byte * 8 + bit)];
        bits |= static_cast<unsigned>(values[pair.first] > values[pair.second]) << bit;
      }
      out[byte] = static_cast<uint8_t>(bits);
    }
  }
}

}  // namespace mono
}  // namespace docking_perception
