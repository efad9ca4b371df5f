#include "docking_perception/mono/face_search.h"

namespace docking_perception {
namespace mono {

FaceSearchOutcome searchFace(const FeatureMatcher& matcher, const cv::Mat& gray, const std::vector<SearchRegion>& priors,
                             bool use_blur_search, int* preferred) {
  FaceSearchOutcome outcome;
  std::vector<int> order = {use_blur_search ? *preferred : 0};
  if (use_blur_search) {
    for (int c = 0; c < kSearchConfigurations; ++c) {
      if (c != order.front() && (c != 2 || matcher.hasBlurredModel())) order.push_back(c);
    }
  }
  auto attempt = [&](const cv::Rect& rect, double face_width_px, int prior_index) {
    for (const int configuration : order) {
      const int level = configuration == 1 ? 1 : 0;
      const bool blurred = configuration != 0 && matcher.hasBlurredModel();
      FaceMatch match = matcher.match(gray, rect, face_width_px, level, blurred);
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
  order.resize(1);
  if (!attempt(cv::Rect(), 0.0, -1) && use_blur_search) {
    int next = (order.front() + 1) % kSearchConfigurations;
    if (!matcher.hasBlurredModel()) next = 1 - std::min(order.front(), 1);
    *preferred = next;
  }
  return outcome;
}

}  // namespace mono
}  // namespace docking_perception
