// IR LED blobs and the 5-point pattern among them.
//
// Blobs: a fixed threshold, 8-connected components, and an intensity-weighted centroid over the blob and
// its skirt (weights I - the local background level) for sub-pixel precision. (Area, fill, aspect and
// contrast filters on the components measured no help on the stress report seeds: removed.)
//
// Pattern: the markers form two collinear triples sharing an end (A = 0-1-2, B = 2-3-4, each middle at
// the midpoint). Perspective keeps lines straight but moves the projected midpoint, so a candidate
// triple (a, m, b) is accepted when m lies within kCollinearityTolerance * |ab| of the line ab and its
// position along ab is within kMidpointTolerance of 0.5. Two triples sharing one end and no other blob
// make a candidate pattern. Which triple is A follows from the face's handedness: a face seen from the
// front keeps the sign of the 2D cross product of the arms (2->0, 2->4) that the model has, whatever
// the arm lengths look like under foreshortening. Candidates are ranked by their geometric residuals;
// an extra blob only adds candidates, a missing one leaves none (a clean failure with a reason).
#pragma once

#include <Eigen/Core>
#include <opencv2/core.hpp>
#include <string>
#include <vector>

#include "docking_perception/mono/collinear_five_point_solver.h"
#include "docking_perception/mono/mono_pose_settings.h"
#include "docking_perception/mono/target_model.h"

namespace docking_perception {
namespace mono {

// LedDetectorParams, the blob and pattern settings, is declared in settings/mono_pose.yaml (generated header).

struct LedBlob {
  Eigen::Vector2d centroid = Eigen::Vector2d::Zero();
  double area_px = 0.0;
  double peak = 0.0;
  double elongation = 1.0;  // ratio of the thresholded component's principal axes
  double streak_sigma_px = 0.0;  // motion streak: sqrt(major - minor second moment), ~0 for a round spot,
                                 // ~L / sqrt(12) for a streak of length L (more for a wide spot's sweep)
};

struct LedPatternCandidate {
  MarkerPixels pixels{};   // pixels[i] is the image of marker i
  std::array<int, kMarkerCount> blob_indices{};
  double score = 0.0;      // sum of normalised collinearity and midpoint residuals (lower is better)
};

// The median streak_sigma_px of a candidate's five blobs: the motion blur the LEDs show.
double medianStreakSigma(const std::vector<LedBlob>& blobs, const LedPatternCandidate& candidate);

class LedPatternDetector {
 public:
  LedPatternDetector(const MarkerPoints& markers, const LedDetectorParams& params = LedDetectorParams());
  void setParams(const LedDetectorParams& params) { params_ = params; }
  const LedDetectorParams& params() const { return params_; }

  // Blobs in an 8-bit single-channel image, within roi (an empty roi means the whole image).
  std::vector<LedBlob> detectBlobs(const cv::Mat& gray, const cv::Rect& roi = cv::Rect()) const;

  // All candidate patterns, best first. Empty (with the reason) when none is found.
  std::vector<LedPatternCandidate> identifyPattern(const std::vector<LedBlob>& blobs, std::string* reason) const;

 private:
  LedDetectorParams params_;
  double expected_handedness_;  // sign of cross(arm 2->0, arm 2->4) in the image of a front-facing face
};

}  // namespace mono
}  // namespace docking_perception
