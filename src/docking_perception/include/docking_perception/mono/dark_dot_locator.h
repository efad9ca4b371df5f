// Locates one printed dark dot near a predicted pixel (the dot's model position mapped through the
// face homography) with sub-pixel precision: inside a disc around the prediction, the background level
// is a high percentile and the dot level the minimum; pixels darker than their midpoint are weighted
// by how much darker they are, and the weighted centroid is iterated twice (re-centring the disc).
#pragma once

#include <Eigen/Core>
#include <opencv2/core.hpp>
#include <string>
#include <vector>

#include "docking_perception/mono/led_pattern_detector.h"


namespace docking_perception {
namespace mono {

class DarkDotLocator {
 public:

  // gray: 8-bit; predicted: pixel; radius_px: the dot's apparent radius. False with the reason when the
  // disc leaves the image, has too little contrast, or the centre runs away.
  bool locate(const cv::Mat& gray, const Eigen::Vector2d& predicted, double radius_px, Eigen::Vector2d* centre,
              std::string* reason) const;
};

// Dark dots anywhere in an image, with no prior: the candidates for the printed reference dots (dark discs,
// each on a white ring) from which the cold search (no track, no hint) identifies the 5-point pattern, at any
// roll and under blur, as the IR instance does with its LEDs. Each dot radius is looked for on the pyramid
// level where it is 2-4 px: a pixel is a candidate when it is the darkest of its 3x3 neighbourhood and the
// circle of 1.4 radii around it (the white ring, or the print around it) is brighter; its strength is how
// much brighter the third-darkest of 8 samples on that circle is (a motion smear darkens the two samples
// along it). The strongest per place, strongest first; centres refined by DarkDotLocator.
class DarkDotFinder {
 public:
  // radii_px: the dot radii to look for (e.g. from the model pyramid's face widths).
  explicit DarkDotFinder(std::vector<double> radii_px = {});
  // Per radius (in the order given), at most max_per_radius dots, strongest first; `centroid` sub-pixel,
  // `area_px` the disc of the radius, `peak` the strength (8-bit levels).
  std::vector<std::vector<LedBlob>> find(const cv::Mat& gray, size_t max_per_radius) const;
  const std::vector<double>& radii() const { return radii_px_; }

 private:
  struct Candidate {
    Eigen::Vector2d centre;
    double radius_px;
    double strength;
  };
  std::vector<LedBlob> strongestDots(const cv::Mat& gray, std::vector<Candidate> candidates, size_t max_dots) const;
  // The candidates of the radii (indices into radii_px_) that share this pyramid level, into (*found)[index].
  void findOnLevel(const cv::Mat& level, int level_index, const std::vector<size_t>& radii,
                   std::vector<std::vector<Candidate>>* found) const;
  std::vector<double> radii_px_;
  std::vector<std::vector<size_t>> radii_of_level_;  // indices into radii_px_, per pyramid level
  DarkDotLocator locator_;
};

}  // namespace mono
}  // namespace docking_perception
