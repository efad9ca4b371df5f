// Locates one printed dark dot near a predicted pixel (the dot's model position mapped through the
// face homography) with sub-pixel precision: inside a disc around the prediction, the background level
// is a high percentile and the dot level the minimum; pixels darker than their midpoint are weighted
// by how much darker they are, and the weighted centroid is iterated twice (re-centring the disc).
#pragma once

#include <Eigen/Core>
#include <opencv2/core.hpp>
#include <string>


namespace docking_perception {
namespace mono {

class DarkDotLocator {
 public:

  // gray: 8-bit; predicted: pixel; radius_px: the dot's apparent radius. False with the reason when the
  // disc leaves the image, has too little contrast, or the centre runs away.
  bool locate(const cv::Mat& gray, const Eigen::Vector2d& predicted, double radius_px, Eigen::Vector2d* centre,
              std::string* reason) const;
};

}  // namespace mono
}  // namespace docking_perception
