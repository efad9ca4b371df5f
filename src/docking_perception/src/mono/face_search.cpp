#include "docking_perception/mono/face_search.h"

#include <algorithm>

namespace docking_perception {
namespace mono {
namespace {

int imageLevel(int configuration) { return configuration == 1 ? 1 : 0; }

ModelSet modelSet(int configuration) {
  return configuration == 0 ? ModelSet::kSharp : configuration == 3 ? ModelSet::kRowSmeared : ModelSet::kBlurred;
}

}  // namespace

FaceSearchOutcome searchFace(const FeatureMatcher& matcher, const cv::Mat& gray, const std::vector<SearchRegion>& priors,
                             bool use_blur_search, int* preferred, bool full_frame) {
  FaceSearchOutcome outcome;
  // The configurations this matcher has (its model sets), in order.
  std::vector<int> available = {0};
  if (use_blur_search) {
    // Half resolution searches with the sharp model when there is no blurred one.
    for (int c = 1; c < kSearchConfigurations; ++c) {
      if (c == 1 || matcher.hasModelSet(modelSet(c))) available.push_back(c);
    }
  }
  if (std::find(available.begin(), available.end(), *preferred) == available.end()) *preferred = 0;
  std::vector<int> order = {*preferred};
  for (const int c : available) {
    if (c != *preferred) order.push_back(c);
  }
  auto attempt = [&](const cv::Rect& rect, double face_width_px, int prior_index) {
    for (const int configuration : order) {
      FaceMatch match = matcher.match(gray, rect, face_width_px, imageLevel(configuration), modelSet(configuration));
      ++outcome.attempts;
      // Nothing found: the last attempt (the full frame) says why.
      outcome.match = match;
      outcome.region = rect.area() > 0 ? rect : cv::Rect(0, 0, gray.cols, gray.rows);
      outcome.prior_index = prior_index;
      if (match.found) {
        *preferred = configuration;
        return true;
      }
    }
    return false;
  };
  for (size_t i = 0; i < priors.size(); ++i) {
    if (priors[i].rect.area() <= 0) continue;
    if (attempt(priors[i].rect, priors[i].face_width_px, static_cast<int>(i))) return outcome;
  }
  // The full frame costs a whole keypoint budget per configuration: one configuration per image, the
  // next one on the next image (a cold start under blur takes up to kSearchConfigurations images, and
  // no image costs more than one full-frame search).
  if (!full_frame) return outcome;
  order.resize(1);
  if (!attempt(cv::Rect(), 0.0, -1)) {
    const auto current = std::find(available.begin(), available.end(), order.front());
    *preferred = available[static_cast<size_t>(current - available.begin() + 1) % available.size()];
  }
  return outcome;
}

}  // namespace mono
}  // namespace docking_perception
