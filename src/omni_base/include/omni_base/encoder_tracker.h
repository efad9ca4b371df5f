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

/// One reading of the counters, stamped on two clocks.
struct EncoderFrame {
  std::vector<int32_t> counts;
  uint32_t source_time_ms{0};  ///< when the counts were latched, on the board's clock (ms since its boot, wraps)
  double host_time_s{0.0};     ///< when the host received them
};

/// What happened to a sample; the node reacts to these codes, never to the reason text.
enum class EncoderEvent {
  kAccepted,          ///< counted
  kBaseline,          ///< first sample: the baseline, no motion
  kBoardRebooted,     ///< the board restarted: its counts since boot are counted, the clock re-anchored
  kWrongWheelCount,   ///< rejected
  kImplausibleJump,   ///< rejected: faster than the plausible wheel speed over the board time elapsed
  kClockJumped,       ///< rejected: board clock ahead of what the host clock allows (a corrupted time)
  kClockBackwards,    ///< rejected: board clock went back, but the counts do not look like a fresh boot
  kRebaselined,       ///< rejected several times in a row: the new counts and clock are the baseline
};

/// Tracks each wheel's counter across roll-over. Motion is measured between accepted samples on the
/// board's own clock, so samples that reach the host late or in bursts are counted exactly. A
/// rejected sample moves nothing and does not move the baseline: the next good sample carries the
/// motion. A reboot (board clock restarting, counts consistent with motion since boot) counts the
/// counts since boot instead of jumping by the old counter values.
class EncoderTracker {
 public:
  /// The board clock may lead the host clock by this much more than the least lead seen (host clock
  /// steps, scheduling jitter); more is a corrupted board time.
  static constexpr double kClockLeadToleranceS = 0.5;

  struct Sample {
    EncoderEvent event{EncoderEvent::kWrongWheelCount};
    std::vector<double> delta_rad;    ///< wheel angle change since the last accepted sample (counted ones)
    double dt_s{0.0};                 ///< board time the delta spans (0 for a baseline)
    std::string reason;               ///< for the log
    bool accepted() const {
      return event == EncoderEvent::kAccepted || event == EncoderEvent::kBaseline ||
             event == EncoderEvent::kBoardRebooted || event == EncoderEvent::kRebaselined;
    }
  };

  explicit EncoderTracker(const EncoderTrackerConfig& config);

  Sample update(const EncoderFrame& frame);
  /// Forget the baseline (the next sample is a new baseline, no motion).
  void reset();

  const std::vector<double>& positions() const { return positions_rad_; }
  std::uint64_t rejectedSamples() const { return rejected_samples_; }
  std::uint64_t rebaselines() const { return rebaselines_; }
  std::uint64_t reboots() const { return reboots_; }

  /// Signed difference of two wrapping counter values, in (-2^(bits-1), 2^(bits-1)].
  static int64_t wrappedDifference(int64_t current, int64_t previous, int bits);

 private:
  struct Anchor {
    std::vector<int32_t> counts;
    uint32_t source_time_ms{0};
    double host_time_s{0.0};
    int64_t source_time_unwrapped_ms{0};
  };

  double maxCounts(double dt_s) const;
  bool countsPlausible(const std::vector<int64_t>& deltas, double dt_s, std::size_t* bad_wheel) const;
  bool looksLikeFreshBoot(const EncoderFrame& frame, int64_t board_dt_ms) const;
  Sample count(const EncoderFrame& frame, const std::vector<int64_t>& deltas, double dt_s, EncoderEvent event);
  Sample reject(EncoderEvent event, std::string reason, const EncoderFrame& frame);
  void anchorClock(const EncoderFrame& frame);

  EncoderTrackerConfig config_;
  std::optional<Anchor> anchor_;       ///< the last accepted sample
  double min_clock_lag_s_{0.0};        ///< least (host time - board time) seen since the clock was anchored
  std::vector<double> positions_rad_;
  int consecutive_rejections_{0};
  std::uint64_t rejected_samples_{0};
  std::uint64_t rebaselines_{0};
  std::uint64_t reboots_{0};
};

}  // namespace omni_base
