#include "omni_base/encoder_tracker.h"

#include <cmath>
#include <stdexcept>

namespace omni_base {

EncoderTracker::EncoderTracker(const EncoderTrackerConfig& config)
    : config_(config), positions_rad_(config.wheel_count, 0.0) {
  if (config_.wheel_count == 0) throw std::invalid_argument("encoder tracker needs at least one wheel");
  if (!(config_.counts_per_rev > 0.0)) throw std::invalid_argument("encoder counts per revolution must be positive");
  if (config_.counter_bits < 8 || config_.counter_bits > 32) {
    throw std::invalid_argument("encoder counter width must be 8 to 32 bits");
  }
  if (!(config_.max_plausible_rad_s > 0.0)) throw std::invalid_argument("max plausible wheel speed must be positive");
}

int64_t EncoderTracker::wrappedDifference(int64_t current, int64_t previous, int bits) {
  const int64_t modulus = int64_t{1} << bits;
  const int64_t half = modulus / 2;
  int64_t diff = (current - previous) % modulus;
  if (diff < 0) diff += modulus;
  if (diff > half) diff -= modulus;
  return diff;
}

void EncoderTracker::reset() {
  baseline_.reset();
  consecutive_rejections_ = 0;
}

EncoderTracker::Sample EncoderTracker::update(const std::vector<int32_t>& counts, double dt_s) {
  Sample sample;
  if (counts.size() != config_.wheel_count) {
    sample.reason = "expected " + std::to_string(config_.wheel_count) + " encoder counts, got " +
                    std::to_string(counts.size());
    ++rejected_samples_;
    return sample;
  }
  if (!baseline_) {
    baseline_ = counts;
    sample.accepted = true;
    sample.rebaselined = true;
    sample.delta_rad.assign(config_.wheel_count, 0.0);
    return sample;
  }
  const double rad_per_count = 2.0 * M_PI / config_.counts_per_rev;
  // Allow a couple of counts of quantisation on top of the fastest plausible motion.
  const double max_counts = config_.max_plausible_rad_s * std::max(dt_s, 0.0) / rad_per_count + 2.0;
  std::vector<double> delta(config_.wheel_count);
  for (std::size_t i = 0; i < counts.size(); ++i) {
    const int64_t d = wrappedDifference(counts[i], (*baseline_)[i], config_.counter_bits);
    if (std::abs(static_cast<double>(d)) > max_counts) {
      sample.reason = "wheel " + std::to_string(i) + " jumped " + std::to_string(d) + " counts in " +
                      std::to_string(dt_s) + " s (limit " + std::to_string(static_cast<int64_t>(max_counts)) + ")";
      ++rejected_samples_;
      if (++consecutive_rejections_ >= config_.rebaseline_after_rejections) {
        baseline_ = counts;
        consecutive_rejections_ = 0;
        ++rebaselines_;
        sample.rebaselined = true;
        sample.reason += "; counters re-baselined";
      }
      return sample;
    }
    delta[i] = static_cast<double>(d) * rad_per_count;
  }
  consecutive_rejections_ = 0;
  baseline_ = counts;
  for (std::size_t i = 0; i < delta.size(); ++i) positions_rad_[i] += delta[i];
  sample.accepted = true;
  sample.delta_rad = std::move(delta);
  return sample;
}

}  // namespace omni_base
