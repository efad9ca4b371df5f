// Turns raw, wrapping encoder counts into wheel angle increments (ROS-free).
#pragma once

#include <cstdint>
#include <optional>
#include <string>
#include <vector>

namespace omni_base {

struct EncoderTrackerConfig {
  std::size_t wheel_count{3};
  double counts_per_rev{1320.0};
  int counter_bits{32};                 ///< the board's counters wrap modulo 2^bits
  double max_plausible_rad_s{40.0};     ///< a larger apparent speed is a glitch, not motion
  int rebaseline_after_rejections{3};   ///< consecutive rejected samples before trusting the new counts
};

/// Tracks each wheel's counter across roll-over and rejects implausible jumps (a corrupted value, a
/// board that reset its counters). A rejected sample moves nothing; after a few consecutive
/// rejections the tracker accepts the new counts as its baseline (reported, so it is visible).
class EncoderTracker {
 public:
  struct Sample {
    bool accepted{false};             ///< deltas below are valid
    bool rebaselined{false};          ///< the baseline was (re)set: first sample, or after rejections
    std::vector<double> delta_rad;    ///< wheel angle change since the last accepted sample
    std::string reason;               ///< why it was rejected
  };

  explicit EncoderTracker(const EncoderTrackerConfig& config);

  /// dt_s: time the counts span since the previous sample (board time where the board reports it).
  Sample update(const std::vector<int32_t>& counts, double dt_s);
  /// Forget the baseline (e.g. after a reconnect: the board may have restarted).
  void reset();

  const std::vector<double>& positions() const { return positions_rad_; }
  std::uint64_t rejectedSamples() const { return rejected_samples_; }
  std::uint64_t rebaselines() const { return rebaselines_; }

  /// Signed difference of two wrapping counter values, in (-2^(bits-1), 2^(bits-1)].
  static int64_t wrappedDifference(int64_t current, int64_t previous, int bits);

 private:
  EncoderTrackerConfig config_;
  std::optional<std::vector<int32_t>> baseline_;
  std::vector<double> positions_rad_;
  int consecutive_rejections_{0};
  std::uint64_t rejected_samples_{0};
  std::uint64_t rebaselines_{0};
};

}  // namespace omni_base
