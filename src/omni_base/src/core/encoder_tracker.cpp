#include "omni_base/encoder_tracker.h"

#include <algorithm>
#include <cmath>
#include <stdexcept>

namespace omni_base {
namespace {

constexpr int kBoardClockBits = 32;         // the board time is a u32 of milliseconds
constexpr double kQuantisationCounts = 2.0;  // counts allowed on top of the fastest plausible motion

}  // namespace

EncoderTracker::EncoderTracker(const EncoderTrackerConfig& config)
    : config_(config), positions_rad_(config.wheel_count, 0.0) {
  if (config_.wheel_count == 0) throw std::invalid_argument("encoder tracker needs at least one wheel");
  if (!(config_.counts_per_rev > 0.0)) throw std::invalid_argument("encoder counts per revolution must be positive");
  if (config_.counter_bits < 8 || config_.counter_bits > 32) {
    throw std::invalid_argument("encoder counter width must be 8 to 32 bits");
  }
  if (!(config_.max_plausible_rad_s > 0.0)) throw std::invalid_argument("max plausible wheel speed must be positive");
  if (config_.rebaseline_after_rejections < 1) throw std::invalid_argument("re-baseline count must be at least 1");
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
  anchor_.reset();
  consecutive_rejections_ = 0;
}

double EncoderTracker::maxCounts(double dt_s) const {
  const double rad_per_count = 2.0 * M_PI / config_.counts_per_rev;
  return config_.max_plausible_rad_s * std::max(dt_s, 0.0) / rad_per_count + kQuantisationCounts;
}

bool EncoderTracker::countsPlausible(const std::vector<int64_t>& deltas, double dt_s, std::size_t* bad_wheel) const {
  const double limit = maxCounts(dt_s);
  for (std::size_t i = 0; i < deltas.size(); ++i) {
    if (std::abs(static_cast<double>(deltas[i])) > limit) {
      if (bad_wheel) *bad_wheel = i;
      return false;
    }
  }
  return true;
}

bool EncoderTracker::looksLikeFreshBoot(const EncoderFrame& frame, int64_t board_dt_ms) const {
  const double uptime_s = frame.source_time_ms * 1e-3;
  const double host_silence_s = frame.host_time_s - anchor_->host_time_s;
  // The clock restarted: it went back (to a smaller value: a corrupted time 2^31 ms ahead also reads as
  // "back"), or the board has been up for less time than we have not heard from it.
  const bool went_back = board_dt_ms < 0 && frame.source_time_ms < anchor_->source_time_ms;
  const bool clock_restarted = went_back || uptime_s + kClockLeadToleranceS < host_silence_s;
  if (!clock_restarted) return false;
  // A fresh boot starts its counters at zero: they can only hold the motion since boot.
  std::vector<int64_t> since_boot(frame.counts.size());
  for (std::size_t i = 0; i < frame.counts.size(); ++i) {
    since_boot[i] = wrappedDifference(frame.counts[i], 0, config_.counter_bits);
  }
  return countsPlausible(since_boot, uptime_s, nullptr);
}

void EncoderTracker::anchorClock(const EncoderFrame& frame) {
  anchor_ = Anchor{frame.counts, frame.source_time_ms, frame.host_time_s, frame.source_time_ms};
  min_clock_lag_s_ = frame.host_time_s - frame.source_time_ms * 1e-3;
}

EncoderTracker::Sample EncoderTracker::count(const EncoderFrame& frame, const std::vector<int64_t>& deltas,
                                             double dt_s, EncoderEvent event) {
  const double rad_per_count = 2.0 * M_PI / config_.counts_per_rev;
  Sample sample;
  sample.event = event;
  sample.dt_s = dt_s;
  sample.delta_rad.resize(deltas.size());
  for (std::size_t i = 0; i < deltas.size(); ++i) {
    sample.delta_rad[i] = static_cast<double>(deltas[i]) * rad_per_count;
    positions_rad_[i] += sample.delta_rad[i];
  }
  anchor_->counts = frame.counts;
  anchor_->source_time_ms = frame.source_time_ms;
  anchor_->host_time_s = frame.host_time_s;
  consecutive_rejections_ = 0;
  return sample;
}

EncoderTracker::Sample EncoderTracker::reject(EncoderEvent event, std::string reason, const EncoderFrame& frame) {
  ++rejected_samples_;
  if (++consecutive_rejections_ < config_.rebaseline_after_rejections) {
    Sample sample;
    sample.event = event;
    sample.reason = std::move(reason);
    return sample;
  }
  // Persistent: the board's clock or counters really moved. Re-anchor the clock on this frame, and keep
  // the motion since the last accepted sample if the host clock makes it plausible.
  ++rebaselines_;
  const Anchor previous = *anchor_;
  std::vector<int64_t> deltas(frame.counts.size());
  for (std::size_t i = 0; i < deltas.size(); ++i) {
    deltas[i] = wrappedDifference(frame.counts[i], previous.counts[i], config_.counter_bits);
  }
  const double host_dt_s = frame.host_time_s - previous.host_time_s;
  const bool keep = countsPlausible(deltas, host_dt_s, nullptr);
  if (!keep) std::fill(deltas.begin(), deltas.end(), 0);
  anchorClock(frame);
  Sample sample = count(frame, deltas, keep ? host_dt_s : 0.0, EncoderEvent::kRebaselined);
  sample.reason = reason + (keep ? "; re-baselined, motion kept" : "; re-baselined, motion since the last good sample lost");
  return sample;
}

EncoderTracker::Sample EncoderTracker::update(const EncoderFrame& frame) {
  if (frame.counts.size() != config_.wheel_count) {
    ++rejected_samples_;
    Sample sample;
    sample.event = EncoderEvent::kWrongWheelCount;
    sample.reason = "expected " + std::to_string(config_.wheel_count) + " encoder counts, got " +
                    std::to_string(frame.counts.size());
    return sample;
  }
  if (!anchor_) {
    anchorClock(frame);
    Sample sample;
    sample.event = EncoderEvent::kBaseline;
    sample.delta_rad.assign(config_.wheel_count, 0.0);
    return sample;
  }
  const int64_t board_dt_ms = wrappedDifference(frame.source_time_ms, anchor_->source_time_ms, kBoardClockBits);
  if (looksLikeFreshBoot(frame, board_dt_ms)) {
    ++reboots_;
    std::vector<int64_t> since_boot(frame.counts.size());
    for (std::size_t i = 0; i < since_boot.size(); ++i) {
      since_boot[i] = wrappedDifference(frame.counts[i], 0, config_.counter_bits);
    }
    anchorClock(frame);
    Sample sample = count(frame, since_boot, frame.source_time_ms * 1e-3, EncoderEvent::kBoardRebooted);
    sample.reason = "board rebooted (clock restarted at " + std::to_string(frame.source_time_ms) + " ms)";
    return sample;
  }
  if (board_dt_ms < 0) {
    return reject(EncoderEvent::kClockBackwards,
                  "board clock went back " + std::to_string(-board_dt_ms) + " ms without a reboot", frame);
  }
  const int64_t source_unwrapped_ms = anchor_->source_time_unwrapped_ms + board_dt_ms;
  const double clock_lag_s = frame.host_time_s - source_unwrapped_ms * 1e-3;
  if (clock_lag_s < min_clock_lag_s_ - kClockLeadToleranceS) {
    return reject(EncoderEvent::kClockJumped,
                  "board clock jumped " + std::to_string(board_dt_ms) + " ms ahead of the host clock", frame);
  }
  std::vector<int64_t> deltas(frame.counts.size());
  for (std::size_t i = 0; i < deltas.size(); ++i) {
    deltas[i] = wrappedDifference(frame.counts[i], anchor_->counts[i], config_.counter_bits);
  }
  const double dt_s = board_dt_ms * 1e-3;
  std::size_t bad_wheel = 0;
  if (!countsPlausible(deltas, dt_s, &bad_wheel)) {
    return reject(EncoderEvent::kImplausibleJump,
                  "wheel " + std::to_string(bad_wheel) + " jumped " + std::to_string(deltas[bad_wheel]) +
                      " counts in " + std::to_string(dt_s) + " s of board time (limit " +
                      std::to_string(static_cast<int64_t>(maxCounts(dt_s))) + ")",
                  frame);
  }
  min_clock_lag_s_ = std::min(min_clock_lag_s_, clock_lag_s);
  anchor_->source_time_unwrapped_ms = source_unwrapped_ms;
  return count(frame, deltas, dt_s, EncoderEvent::kAccepted);
}

}  // namespace omni_base
