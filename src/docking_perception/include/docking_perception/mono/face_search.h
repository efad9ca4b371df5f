// Where and at which image scale mono_pose looks for the textured face (issue 11: find the target under
// blur and clutter within the CPU budget).
//
// Order: the regions a prior gives (the pose predicted from the last frame; an external hint, e.g. the
// disparity detector's target projected into this image), then the full frame (MonoPoseEstimator looks for
// the printed dots in between: full_frame false). In each region the
// configuration that found the face last is tried first (blur persists from frame to frame), then the
// others: full resolution keeps fine corners (far, sharp faces), half resolution finds the coarse corners
// that remain in a blurred image, and a blurred model pyramid gives the descriptors blurred corners have. A region spends the whole keypoint budget on itself, which is what
// finds a target over a busy background once any prior exists.
#pragma once

#include <opencv2/core.hpp>
#include <vector>

#include "docking_perception/mono/feature_matcher.h"

namespace docking_perception {
namespace mono {

struct SearchRegion {
  cv::Rect rect;               // clipped to the image by the caller
  double face_width_px = 0.0;  // expected apparent face width (0: unknown)
};

struct FaceSearchOutcome {
  FaceMatch match;
  cv::Rect region;             // where the match that decided was searched
  int prior_index = -1;        // index of the prior region that gave the match, -1: the full frame
  int attempts = 0;            // matcher calls
};

// The ways to look in one region: (image level, model set). 0: full resolution, sharp model (sharp
// faces); 1: half resolution, blurred model (strong blur); 2: full resolution, blurred model (moderate
// blur on a small, far face that half resolution would shrink below the model's smallest level); 3: full
// resolution, the row-smeared model (a far face smeared by the robot's yaw or drive), when it is built.
constexpr int kSearchConfigurations = 4;

// Prior regions try every configuration (small regions are cheap); the full frame tries one per image
// and moves *preferred on to the next after a failure (round robin over images).
// preferred: in/out, the configuration that found the face last. use_blur_search: false searches
// configuration 0 only; configurations with the blurred model need it built. full_frame false: the priors only.
FaceSearchOutcome searchFace(const FeatureMatcher& matcher, const cv::Mat& gray, const std::vector<SearchRegion>& priors,
                             bool use_blur_search, int* preferred, bool full_frame = true);

}  // namespace mono
}  // namespace docking_perception
