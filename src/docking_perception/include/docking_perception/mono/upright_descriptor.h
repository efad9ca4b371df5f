// A binary descriptor without orientation, for a face that stays upright in the image (issue 15).
//
// On the test bed both robots stand on one floor with level cameras, so the face's image is never
// turned by more than a few degrees about the optical axis (the stress scenes draw up to +-10 deg).
// OpenCV's BRISK spends about half of its ~65 k instructions a keypoint finding an orientation (60
// smoothed samples, 870 gradient pairs) and the rest on a second, rotated set of 60 samples read through
// an integral image of the whole frame. This descriptor keeps BRISK's idea (smoothed intensities on
// concentric rings, one bit per short pair: is the first brighter than the second) and drops the
// rotation: 60 box-smoothed samples at fixed offsets, read straight from the image, and 512 bits from
// the 512 shortest pairs. About 7 k instructions a keypoint (callgrind); 64 bytes, so the Hamming
// matcher is the same. Scale comes from the model pyramid, as with FAST corners before (which BRISK
// gave one scale).
// A camera that can roll (the flight vehicle) needs the rotation-invariant BRISK descriptor instead
// (FeatureMatcherParams::upright_descriptors = false). The blurred model keeps BRISK (feature_matcher.h).
#pragma once

#include <array>
#include <cstdint>
#include <utility>
#include <vector>
#include <opencv2/core.hpp>

namespace docking_perception {
namespace mono {

class UprightRingDescriptor {
 public:
  static constexpr int kSamples = 60;
  static constexpr int kBits = 512;
  static constexpr int kBytes = kBits / 8;

  UprightRingDescriptor();

  // Pixels between a keypoint and the image border for its samples to lie inside the image.
  int borderPx() const { return border_px_; }

  // Descriptors (one CV_8UC1 row of kBytes per keypoint) of an 8-bit gray image. Keypoints whose
  // samples would leave the image are removed from *keypoints, so row i describes (*keypoints)[i].
  void compute(const cv::Mat& gray, std::vector<cv::KeyPoint>* keypoints, cv::Mat* descriptors) const;

 private:
  struct Sample {
    int dx;
    int dy;
    int half_box;  // the smoothing box is (2 half_box + 1)^2 pixels
  };
  // The 60 smoothed intensities around (x, y), each scaled to one common box area so they compare.
  void sampleRing(const cv::Mat& gray, int x, int y, int32_t* values) const;

  std::array<Sample, kSamples> samples_;
  std::array<int32_t, kSamples> area_scale_;  // common area / this sample's box area
  std::array<std::pair<uint8_t, uint8_t>, kBits> pairs_;
  int border_px_ = 0;
};

}  // namespace mono
}  // namespace docking_perception
