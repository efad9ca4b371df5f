#include "docking_perception/arbiter/source_arbiter.h"

#include <cmath>
#include <cstdio>
#include <stdexcept>
#include <vector>

namespace docking_perception {
namespace arbiter {
namespace {

std::size_t indexOf(Source source) { return static_cast<std::size_t>(source); }

std::string formatDouble(const char* format, double value) {
  char buffer[64];
  std::snprintf(buffer, sizeof(buffer), format, value);
  return buffer;
}

bool isMono(Source source) { return source != Source::kDisparity; }

}  // namespace

const char* sourceName(Source source) {
  switch (source) {
    case Source::kDisparity:
      return "disparity";
    case Source::kMonoVisible:
      return "mono_visible";
    case Source::kMonoIr:
      return "mono_ir";
  }
  return "unknown";
}

const char* regimeName(RangeRegime regime) {
  switch (regime) {
    case RangeRegime::kUnknown:
      return "range unknown";
    case RangeRegime::kFar:
      return "far";
    case RangeRegime::kNear:
      return "near";
  }
  return "unknown";
}

void validate(const ArbiterConfig& c) {
  if (!std::isfinite(c.switch_range_m) || c.switch_range_m <= 0.0) {
    throw std::invalid_argument("switch_range_m must be a positive number of metres");
  }
  if (!std::isfinite(c.hysteresis_m) || c.hysteresis_m < 0.0 || c.hysteresis_m >= c.switch_range_m) {
    throw std::invalid_argument("hysteresis_m must be in [0, switch_range_m)");
  }
  if (!std::isfinite(c.timeout_s) || c.timeout_s <= 0.0) {
    throw std::invalid_argument("timeout_s must be a positive number of seconds");
  }
  if (!std::isfinite(c.future_tolerance_s) || c.future_tolerance_s < 0.0) {
    throw std::invalid_argument("future_tolerance_s must be >= 0");
  }
  if (!std::isfinite(c.max_mono_reprojection_error_px) || c.max_mono_reprojection_error_px <= 0.0) {
    throw std::invalid_argument("max_mono_reprojection_error_px must be positive");
  }
  if (!std::isfinite(c.min_disparity_range_m) || c.min_disparity_range_m < 0.0) {
    throw std::invalid_argument("min_disparity_range_m must be a number >= 0");
  }
}

SourceArbiter::SourceArbiter(const ArbiterConfig& config) : config_(config) { validate(config_); }

void SourceArbiter::reconfigure(const ArbiterConfig& config) {
  validate(config);
  config_ = config;
}

const std::optional<EstimateSummary>& SourceArbiter::latest(Source source) const {
  return latest_.at(indexOf(source));
}

OfferResult SourceArbiter::offer(const EstimateSummary& estimate) {
  OfferResult result;
  if (indexOf(estimate.source) >= kSourceCount) {
    ++rejected_;
    result.reason = "unknown source";
    return result;
  }
  if (!std::isfinite(estimate.stamp_s)) {
    ++rejected_;
    result.reason = std::string(sourceName(estimate.source)) + ": stamp is not finite";
    return result;
  }
  auto& slot = latest_[indexOf(estimate.source)];
  if (slot && estimate.stamp_s <= slot->stamp_s) {
    ++rejected_;
    result.reason = std::string(sourceName(estimate.source)) + ": out of order (stamp " +
                    formatDouble("%.3f", estimate.stamp_s) + " s not after the last one, " +
                    formatDouble("%.3f", slot->stamp_s) + " s)";
    return result;
  }
  slot = estimate;
  // A valid flag with non-finite numbers is not a usable estimate: keep it (it is the source's
  // latest word), but as invalid, with the reason.
  if (slot->valid && !std::isfinite(slot->range_m)) {
    slot->valid = false;
    slot->status = "range is not finite";
  } else if (slot->valid && !slot->values_finite) {
    slot->valid = false;
    slot->status = "pose or twist contains NaN";
  }
  result.accepted = true;
  return result;
}

std::string SourceArbiter::unusableReason(const EstimateSummary& e, double now_s) const {
  if (!e.valid) return e.status.empty() ? "no target" : "no target (" + e.status + ")";
  if (!e.position_valid) return "no position";
  if (isMono(e.source) && !e.orientation_valid) return "no orientation";
  if (e.source == Source::kDisparity && e.range_m < config_.min_disparity_range_m) {
    // Near the target the detector sees a blob of the nearest surface (or the background), not the
    // port: its position is then worse than none.
    return "too near (" + formatDouble("%.2f", e.range_m) + " m < " +
           formatDouble("%.2f", config_.min_disparity_range_m) + " m)";
  }
  const double age = now_s - e.stamp_s;
  if (age > config_.timeout_s) return "stale (" + formatDouble("%.2f", age) + " s old)";
  if (age < -config_.future_tolerance_s) {
    return "stamped " + formatDouble("%.2f", -age) + " s in the future";
  }
  return {};
}

std::string SourceArbiter::poorQualityReason(const EstimateSummary& e) const {
  if (!isMono(e.source)) return {};
  const std::uint32_t min_inliers =
      e.source == Source::kMonoIr ? config_.min_ir_inliers : config_.min_visible_inliers;
  if (e.feature_inliers < min_inliers) {
    return "poor (" + std::to_string(e.feature_inliers) + " inliers < " + std::to_string(min_inliers) + ")";
  }
  if (!std::isfinite(e.reprojection_error_px) ||
      e.reprojection_error_px > config_.max_mono_reprojection_error_px) {
    return "poor (reprojection error " + formatDouble("%.2f", e.reprojection_error_px) + " px > " +
           formatDouble("%.2f", config_.max_mono_reprojection_error_px) + " px)";
  }
  return {};
}

void SourceArbiter::updateRegime(double range_m) {
  const double to_near = config_.switch_range_m - config_.hysteresis_m;
  const double to_far = config_.switch_range_m + config_.hysteresis_m;
  switch (regime_) {
    case RangeRegime::kUnknown:
      regime_ = range_m < config_.switch_range_m ? RangeRegime::kNear : RangeRegime::kFar;
      break;
    case RangeRegime::kFar:
      if (range_m < to_near) regime_ = RangeRegime::kNear;
      break;
    case RangeRegime::kNear:
      if (range_m > to_far) regime_ = RangeRegime::kFar;
      break;
  }
}

Decision SourceArbiter::decide(double now_s) {
  Decision decision;
  std::array<std::string, kSourceCount> why_not{};
  for (std::size_t i = 0; i < kSourceCount; ++i) {
    if (!latest_[i]) {
      why_not[i] = "nothing received";
      continue;
    }
    why_not[i] = unusableReason(*latest_[i], now_s);
    if (why_not[i].empty()) why_not[i] = poorQualityReason(*latest_[i]);
  }
  auto usable = [&](Source s) { return why_not[indexOf(s)].empty(); };

  // The range that drives the regime: the source in use if it is still usable (so a noisy other
  // source cannot flip the regime), else the newest usable estimate.
  std::optional<double> range;
  if (last_output_source_ && usable(*last_output_source_)) {
    range = latest_[indexOf(*last_output_source_)]->range_m;
  } else {
    double newest = -INFINITY;
    for (std::size_t i = 0; i < kSourceCount; ++i) {
      if (why_not[i].empty() && latest_[i]->stamp_s > newest) {
        newest = latest_[i]->stamp_s;
        range = latest_[i]->range_m;
      }
    }
  }
  if (range) updateRegime(*range);
  decision.regime = regime_;

  const std::vector<Source> preference =
      regime_ == RangeRegime::kNear
          ? std::vector<Source>{Source::kMonoVisible, Source::kMonoIr, Source::kDisparity}
          : std::vector<Source>{Source::kDisparity, Source::kMonoVisible, Source::kMonoIr};

  std::string reason = regimeName(regime_);
  if (range) reason += " (" + formatDouble("%.2f", *range) + " m)";
  for (Source s : preference) {
    if (usable(s)) {
      decision.valid = true;
      decision.source = s;
      decision.stamp_s = latest_[indexOf(s)]->stamp_s;
      break;
    }
    reason += std::string(": ") + sourceName(s) + " " + why_not[indexOf(s)];
  }
  if (!decision.valid) {
    decision.reason = "no usable estimate; " + reason;
    return decision;
  }
  reason += std::string(": using ") + sourceName(decision.source);
  decision.reason = reason;

  // Publish each estimate once and keep the output in stamp order across sources.
  decision.is_new = !last_output_stamp_s_ || decision.stamp_s > *last_output_stamp_s_;
  if (decision.is_new) {
    last_output_stamp_s_ = decision.stamp_s;
    last_output_source_ = decision.source;
  } else if (!last_output_source_ || *last_output_source_ != decision.source) {
    decision.reason += " (waiting for one newer than the last published)";
  }
  return decision;
}

}  // namespace arbiter
}  // namespace docking_perception
