#include "docking_perception/image_guard/rate_cap.h"

namespace docking_perception {
namespace image_guard {

bool RateCap::admit(double stamp_s) {
  for (const auto& decision : decisions_) {
    if (decision.first == stamp_s) return decision.second;
  }
  if (max_rate_hz_ <= 0.0) return true;
  const double min_spacing_s = (1.0 - kJitterFraction) / max_rate_hz_;
  bool admitted = !have_admitted_ || stamp_s < last_admitted_s_ || stamp_s - last_admitted_s_ >= min_spacing_s;
  if (admitted) {
    have_admitted_ = true;
    last_admitted_s_ = stamp_s;
  }
  decisions_.emplace_back(stamp_s, admitted);
  if (decisions_.size() > kRememberedStamps) decisions_.pop_front();
  return admitted;
}

}  // namespace image_guard
}  // namespace docking_perception
