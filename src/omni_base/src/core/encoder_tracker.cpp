#include "omni_base/encoder_tracker.h"

#include <algorithm>
#include <cmath>
#include <stdexcept>

namespace omni_base {
namespace {

constexpr int kBoardClockBits = 32;         // the board time is a u32 of milliseconds
constexpr double kQuantisationCounts = 2.0;  // counts allowed on top of the fastest plausible motion

}  // namespace

std::vector<double> EncoderTracker::Sample::wheelVelocities() const {
  std::vector<double> velocity(delta_rad.size(), 0.0);
  if (!(dt_s > 0.0)) return velocity;
  for (std::size_t i = 0; i < velocity.size(); ++i) velocity[i] = delta_rad[i] / dt_s;
  return velocity;
}

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

std::vector<int64_t> EncoderTracker::deltasFrom(const std::vector<int32_t>& counts,
                                                const std::vector<int32_t>& from) const {
  std::vector<int64_t> deltas(counts.size());
  for (std::size_t i = 0; i < counts.size(); ++i) {
    deltas[i] = wrappedDifference(counts[i], from[i], config_.counter_bits);
  }
  return deltas;
}

std::vector<int64_t> EncoderTracker::countsSinceBoot(const EncoderFrame& frame) const {
  // A fresh boot starts its counters at zero: they can only hold the motion since boot.
  return deltasFrom(frame.counts, std::vector<int32_t>(frame.counts.size(), 0));
}

bool EncoderTracker::clockRestarted(const EncoderFrame& frame, int64_t board_dt_ms) const {
  // The clock went back (to a smaller value: a corrupted time 2^31 ms ahead also reads as "back"), or
  // the board has been up for less time than we have not heard from it.
  const double uptime_s = frame.source_time_ms * 1e-3;
  const double host_silence_s = frame.host_time_s - anchor_->host_time_s;
  const bool went_back = board_dt_ms < 0 && frame.source_time_ms < anchor_->source_time_ms;
  return went_back || uptime_s + kClockLeadToleranceS < host_silence_s;
}

EncoderTracker::Sample EncoderTracker::claimReboot(const EncoderFrame& frame) {
  const double uptime_s = frame.source_time_ms * 1e-3;
  const double host_silence_s = frame.host_time_s - anchor_->host_time_s;
  if (uptime_s > host_silence_s + kClockLeadToleranceS) {
    ++refused_reboots_;
    return reject(EncoderEvent::kRebootImplausible,
                  "board clock restarted at " + std::to_string(frame.source_time_ms) +
                      " ms, but the board answered " + std::to_string(host_silence_s) + " s ago",
                  frame);
  }
  std::size_t bad_wheel = 0;
  if (!countsPlausible(countsSinceBoot(frame), uptime_s, &bad_wheel)) {
    ++refused_reboots_;
    return reject(EncoderEvent::kRebootImplausible,
                  "board clock restarted at " + std::to_string(frame.source_time_ms) + " ms, but wheel " +
                      std::to_string(bad_wheel) + " reads " + std::to_string(frame.counts[bad_wheel]) +
                      " counts, more than it could turn since boot",
                  frame);
  }
  pending_reboot_ = PendingReboot{frame, frame, 0};
  Sample sample;
  sample.event = EncoderEvent::kRebootPending;
  sample.reason = "board clock restarted at " + std::to_string(frame.source_time_ms) +
                  " ms: a reboot, if the next frames continue the new clock";
  return sample;
}

bool EncoderTracker::continuesPendingClock(const EncoderFrame& frame) const {
  const PendingReboot& pending = *pending_reboot_;
  const int64_t step_ms = wrappedDifference(frame.source_time_ms, pending.latest.source_time_ms, kBoardClockBits);
  const int64_t since_claim_ms = wrappedDifference(frame.source_time_ms, pending.first.source_time_ms, kBoardClockBits);
  const double host_since_claim_s = frame.host_time_s - pending.first.host_time_s;
  if (step_ms < 0 || since_claim_ms * 1e-3 > host_since_claim_s + kClockLeadToleranceS) return false;
  return countsPlausible(deltasFrom(frame.counts, pending.latest.counts), step_ms * 1e-3, nullptr);
}

EncoderTracker::Sample EncoderTracker::followPendingReboot(const EncoderFrame& frame) {
  if (continuesPendingClock(frame)) {
    pending_reboot_->latest = frame;
    if (++pending_reboot_->confirmations >= kRebootConfirmationFrames) return confirmReboot(frame);
    consecutive_rejections_ = 0;
    Sample sample;
    sample.event = EncoderEvent::kRebootPending;
    sample.reason = "board clock restarted: " + std::to_string(pending_reboot_->confirmations) + " of " +
                    std::to_string(kRebootConfirmationFrames) + " frames continue it";
    return sample;
  }
  // Not the new clock: the old timeline, if it continues there, refutes the claim.
  Sample sample = countOnTimeline(frame);
  if (sample.event == EncoderEvent::kAccepted) {
    pending_reboot_.reset();
    ++refused_reboots_;
    sample.event = EncoderEvent::kRebootRefuted;
    sample.reason = "a claimed reboot was refuted: the board's old clock and counters carry on";
  } else if (sample.event == EncoderEvent::kRebaselined) {
    pending_reboot_.reset();
  }
  return sample;
}

EncoderTracker::Sample EncoderTracker::confirmReboot(const EncoderFrame& frame) {
  ++reboots_;
  pending_reboot_.reset();
  anchorClock(frame);
  Sample sample = count(frame, countsSinceBoot(frame), frame.source_time_ms * 1e-3, EncoderEvent::kBoardRebooted);
  sample.reason = "board rebooted (clock restarted, now at " + std::to_string(frame.source_time_ms) + " ms)";
  return sample;
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
  pending_reboot_.reset();
  const Anchor previous = *anchor_;
  std::vector<int64_t> deltas = deltasFrom(frame.counts, previous.counts);
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
  if (pending_reboot_) return followPendingReboot(frame);
  const int64_t board_dt_ms = wrappedDifference(frame.source_time_ms, anchor_->source_time_ms, kBoardClockBits);
  if (clockRestarted(frame, board_dt_ms)) return claimReboot(frame);
  return countOnTimeline(frame);
}

EncoderTracker::Sample EncoderTracker::countOnTimeline(const EncoderFrame& frame) {
  const int64_t board_dt_ms = wrappedDifference(frame.source_time_ms, anchor_->source_time_ms, kBoardClockBits);
  if (board_dt_ms < 0 || clockRestarted(frame, board_dt_ms)) {
    return reject(EncoderEvent::kClockJumped,
                  "board clock at " + std::to_string(frame.source_time_ms) + " ms does not continue from " +
                      std::to_string(anchor_->source_time_ms) + " ms",
                  frame);
  }
  const int64_t source_unwrapped_ms = anchor_->source_time_unwrapped_ms + board_dt_ms;
  const double clock_lag_s = frame.host_time_s - source_unwrapped_ms * 1e-3;
  if (clock_lag_s < min_clock_lag_s_ - kClockLeadToleranceS) {
    return reject(EncoderEvent::kClockJumped,
                  "board clock jumped " + std::to_string(board_dt_ms) + " ms ahead of the host clock", frame);
  }
  const std::vector<int64_t> deltas = deltasFrom(frame.counts, anchor_->counts);
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

bool castsDoubtOnTheLink(EncoderEvent event) {
  switch (event) {
    case EncoderEvent::kRebootPending:
    case EncoderEvent::kBoardRebooted:
    case EncoderEvent::kRebootRefuted:
    case EncoderEvent::kRebootImplausible:
    case EncoderEvent::kRebaselined:
      return true;
    case EncoderEvent::kAccepted:
    case EncoderEvent::kBaseline:
    case EncoderEvent::kWrongWheelCount:
    case EncoderEvent::kImplausibleJump:
    case EncoderEvent::kClockJumped:
      return false;
  }
  return true;
}

}  // namespace omni_base
