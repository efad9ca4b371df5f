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
  kAccepted,            ///< counted
  kBaseline,            ///< first sample: the baseline, no motion
  kRebootPending,       ///< held: the clock restarted consistently with the host's silence; nothing is
                        ///< counted until kRebootConfirmationFrames frames continue the new clock
  kBoardRebooted,       ///< the reboot is confirmed: the counts since boot are counted, the clock re-anchored
  kRebootRefuted,       ///< a pending reboot was contradicted by this frame of the old timeline, which is counted
  kRebootImplausible,   ///< rejected: the clock restarted, but the board claims to have been up longer than
                        ///< the host went without hearing from it, or counts more than it could have since boot
  kWrongWheelCount,     ///< rejected
  kImplausibleJump,     ///< rejected: faster than the plausible wheel speed over the board time elapsed
  kClockJumped,         ///< rejected: board clock ahead of what the host clock allows (a corrupted time)
  kRebaselined,         ///< rejected several times in a row: the new counts and clock are the baseline
};

/// The link is in doubt after this event: diagnostics report ERROR until it is healthy again.
bool castsDoubtOnTheLink(EncoderEvent event);

/// Tracks each wheel's counter across roll-over. Motion is measured between accepted samples on the
/// board's own clock, so samples that reach the host late or in bursts are counted exactly. A
/// rejected sample moves nothing and does not move the baseline: the next good sample carries the
/// motion.
///
/// A reboot is never taken from one frame: a CRC-valid frame can still be a firmware glitch, a second
/// writer on the port or a replayed log. The clock restarting is a claim; it is believed only when the
/// uptime the board claims fits in the time the host went without hearing from it (it cannot have been up
/// for 2 s if it answered 20 ms ago), the counts since boot fit in that uptime, and the next
/// kRebootConfirmationFrames frames continue the new clock. Until then nothing is counted; a frame that
/// continues the old timeline refutes the claim and is counted as usual. A confirmed reboot counts the
/// counts since boot instead of jumping by the old counter values.
class EncoderTracker {
 public:
  /// The board clock may lead the host clock by this much more than the least lead seen (host clock
  /// steps, scheduling jitter and a host stall that stamps a burst of frames late); more is a corrupted
  /// board time. The same slack applies to a rebooted board's uptime against the host's silence.
  static constexpr double kClockLeadToleranceS = 0.5;
  /// Frames that must continue a restarted clock before the reboot is believed: 0.1 s at the 50 Hz
  /// control rate. A stray frame carries no consistent clock; a real reboot loses nothing by the wait
  /// (its counts since boot are counted at confirmation).
  static constexpr int kRebootConfirmationFrames = 5;

  struct Sample {
    EncoderEvent event{EncoderEvent::kWrongWheelCount};
    std::vector<double> delta_rad;    ///< wheel angle change since the last accepted sample (counted ones)
    double dt_s{0.0};                 ///< board time the delta spans (0 for a baseline)
    std::string reason;               ///< for the log
    /// Each wheel's mean velocity over the sample (rad/s): delta_rad / dt_s; zeros for a baseline (dt_s 0).
    std::vector<double> wheelVelocities() const;
    bool accepted() const {
      return event == EncoderEvent::kAccepted || event == EncoderEvent::kBaseline ||
             event == EncoderEvent::kBoardRebooted || event == EncoderEvent::kRebootRefuted ||
             event == EncoderEvent::kRebaselined;
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
  std::uint64_t refusedReboots() const { return refused_reboots_; }  ///< implausible or refuted claims

  /// Signed difference of two wrapping counter values, in (-2^(bits-1), 2^(bits-1)].
  static int64_t wrappedDifference(int64_t current, int64_t previous, int bits);

 private:
  struct Anchor {
    std::vector<int32_t> counts;
    uint32_t source_time_ms{0};
    double host_time_s{0.0};
    int64_t source_time_unwrapped_ms{0};
  };

  /// A claimed reboot awaiting confirmation: its first frame and the latest that continued its clock.
  struct PendingReboot {
    EncoderFrame first;
    EncoderFrame latest;
    int confirmations{0};
  };

  double maxCounts(double dt_s) const;
  bool countsPlausible(const std::vector<int64_t>& deltas, double dt_s, std::size_t* bad_wheel) const;
  std::vector<int64_t> deltasFrom(const std::vector<int32_t>& counts, const std::vector<int32_t>& from) const;
  std::vector<int64_t> countsSinceBoot(const EncoderFrame& frame) const;
  bool clockRestarted(const EncoderFrame& frame, int64_t board_dt_ms) const;
  bool continuesPendingClock(const EncoderFrame& frame) const;
  Sample claimReboot(const EncoderFrame& frame);
  Sample followPendingReboot(const EncoderFrame& frame);
  Sample confirmReboot(const EncoderFrame& frame);
  Sample countOnTimeline(const EncoderFrame& frame);
  Sample count(const EncoderFrame& frame, const std::vector<int64_t>& deltas, double dt_s, EncoderEvent event);
  Sample reject(EncoderEvent event, std::string reason, const EncoderFrame& frame);
  void anchorClock(const EncoderFrame& frame);

  EncoderTrackerConfig config_;
  std::optional<Anchor> anchor_;       ///< the last accepted sample
  std::optional<PendingReboot> pending_reboot_;
  double min_clock_lag_s_{0.0};        ///< least (host time - board time) seen since the clock was anchored
  std::vector<double> positions_rad_;
  int consecutive_rejections_{0};
  std::uint64_t rejected_samples_{0};
  std::uint64_t rebaselines_{0};
  std::uint64_t reboots_{0};
  std::uint64_t refused_reboots_{0};
};

}  // namespace omni_base
