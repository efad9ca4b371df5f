#include <docking_perception/camera/reconnect_backoff.h>

#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <string>

namespace docking_perception {
namespace camera {

void validateBackoffParams(const BackoffParams& params) {
  if (!std::isfinite(params.initial_s) || params.initial_s <= 0.0) {
    throw std::invalid_argument("initial_s must be a positive number of seconds, got " +
                                std::to_string(params.initial_s));
  }
  if (!std::isfinite(params.max_s) || params.max_s < params.initial_s) {
    throw std::invalid_argument("max_s must be at least initial_s (" + std::to_string(params.initial_s) +
                                " s), got " + std::to_string(params.max_s));
  }
  if (!std::isfinite(params.factor) || params.factor < 1.0) {
    throw std::invalid_argument("factor must be at least 1, got " + std::to_string(params.factor));
  }
}

ReconnectBackoff::ReconnectBackoff(const BackoffParams& params) : params_(params), next_delay_s_(params.initial_s) {
  validateBackoffParams(params_);
}

double ReconnectBackoff::nextDelay() {
  const double delay = next_delay_s_;
  next_delay_s_ = std::min(params_.max_s, next_delay_s_ * params_.factor);
  ++failures_;
  return delay;
}

void ReconnectBackoff::reset() {
  next_delay_s_ = params_.initial_s;
  failures_ = 0;
}

}  // namespace camera
}  // namespace docking_perception
