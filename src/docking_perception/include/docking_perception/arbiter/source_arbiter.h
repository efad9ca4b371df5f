// Chooses which target estimate to trust: stereo disparity far away, a monocular pose near, the IR
// camera when the visible image is dark or washed out, and whatever still works when the preferred
// source drops out. ROS-free: the node converts messages into EstimateSummary and back.
#pragma once

#include <array>
#include <cstdint>
#include <deque>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include <docking_msgs/estimate_check.h>

#include "docking_perception/arbiter/consistency.h"
#include "docking_perception/arbiter/frame_change.h"

namespace docking_perception {
namespace arbiter {

/// The estimators, numbered as TargetEstimate.SOURCE_* so the node can cast between them.
enum class Source : std::uint8_t { kDisparity = 0, kMonoVisible = 1, kMonoIr = 2 };
constexpr std::size_t kSourceCount = 3;

const char* sourceName(Source source);

/// What the arbiter needs to know about one estimate (not the estimate itself).
struct EstimateSummary {
  Source source{Source::kDisparity};
  double stamp_s{0.0};             ///< image stamp, s (any epoch, the same as `now_s` below)
  bool valid{false};               ///< the estimator found the target
  bool position_valid{false};
  bool orientation_valid{false};
  double range_m{0.0};             ///< camera to target, m
  std::uint32_t feature_inliers{0};
  double reprojection_error_px{0.0};
  bool values_finite{true};        ///< the pose (and twist, if valid) contain no NaN or infinity
  std::string status;              ///< the estimator's own reason when not valid
  /// The pose in the arbiter's common (output) frame, for the consistency check; absent: the
  /// estimate is never compared (and never contradicted).
  std::optional<PoseWithCovariance3> pose;
  /// The twist in the common frame when the estimator's is valid (how fast it may move between stamps).
  std::optional<TwistWithCovariance3> twist;
};

// ArbiterConfig, the core's settings, is declared in settings/arbiter.yaml (generated header).

/// Throws std::invalid_argument (ConfigError) naming the first setting its declaration does not allow, or
/// the hysteresis not below the switch range.
void validate(const ArbiterConfig& config);


enum class RangeRegime : std::uint8_t { kUnknown, kFar, kNear };
const char* regimeName(RangeRegime regime);

/// What the decision is, for code (the reason string is for people). Numbered for the status topic.
enum class DecisionCode : std::uint8_t {
  kChosen = 0,                 ///< valid: no comparable source contradicts the chosen one
  kChosenOverDisagreement = 1, ///< valid: a contradicting source was outvoted (see Resolution)
  kNoUsableEstimate = 2,       ///< invalid: no source is usable
  kSourcesDisagree = 3,        ///< invalid: usable sources contradict each other and nothing decides
};
const char* decisionCodeName(DecisionCode code);

/// What decided a disagreement between two sources.
enum class Resolution : std::uint8_t { kNone, kThirdSource, kPreviousOutput };
const char* resolutionName(Resolution resolution);

/// Counts of the consistency check, each comparison of a pair of estimates counted once (decide()
/// runs again on every input and on the timer, with the same estimates).
struct ConsistencyCounts {
  std::uint64_t comparisons{0};        ///< pairs of estimates tested
  std::uint64_t disagreements{0};      ///< of them, failed the gate
  std::uint64_t resolved_by_third_source{0};
  std::uint64_t resolved_by_previous_output{0};
  std::uint64_t undecided{0};          ///< published invalid (kSourcesDisagree)
};

struct Decision {
  bool valid{false};               ///< a source was chosen
  DecisionCode code{DecisionCode::kNoUsableEstimate};
  Resolution resolution{Resolution::kNone};  ///< kChosenOverDisagreement / a rejected source: by what
  /// Sources left out because they contradicted a better-supported one (or, with kSourcesDisagree,
  /// every source in the undecided contradiction).
  std::array<bool, kSourceCount> inconsistent{};
  Source source{Source::kDisparity};
  bool is_new{false};              ///< the chosen estimate has not been returned before: publish it
  double stamp_s{0.0};             ///< stamp of the chosen estimate
  RangeRegime regime{RangeRegime::kUnknown};
  std::string reason;              ///< why this source (or why none)
};

/// Why offer() refused an estimate, as a code (the reason string is for people).
enum class OfferProblem : std::uint8_t {
  kNone = 0,
  kUnknownSource = 1,
  kStampNotFinite = 2,
  kStampInFuture = 3,   ///< beyond stamp_limits.max_future_s ahead of now
  kStampTooOld = 4,     ///< beyond stamp_limits.max_age_s behind now
  kOutOfOrder = 5,      ///< not after the last estimate accepted from that source (or a duplicate)
  kStampUnset = 6,      ///< stamp exactly 0: no stamp
};
const char* offerProblemName(OfferProblem problem);

struct OfferResult {
  bool accepted{false};
  OfferProblem problem{OfferProblem::kNone};
  std::string reason;              ///< why it was rejected
};

class SourceArbiter {
 public:
  /// Throws std::invalid_argument for an invalid configuration.
  explicit SourceArbiter(const ArbiterConfig& config);

  /// Records the latest estimate of one source, received at `now_s`. First, when the clock has jumped
  /// back (sim time reset, bag loop), forgets the ordering state (resetOrdering). Then rejects, leaving
  /// every state unchanged, stamps outside config().stamp_limits of `now_s` (a stamp 1000 s ahead
  /// would otherwise become the latest one that every later estimate is "out of order" against), and
  /// what offer(estimate) rejects.
  OfferResult offer(const EstimateSummary& estimate, double now_s);
  /// Without a clock (offline replays, core tests): rejects stamps that are not finite, or not newer
  /// than the last estimate accepted from that source (out of order or duplicate).
  OfferResult offer(const EstimateSummary& estimate);
  /// Forgets the latest estimates and the output history (the regime stays): after a clock jump back,
  /// stamps of the old timeline mean nothing.
  void resetOrdering();
  std::uint64_t clockJumpsBack() const { return clock_jumps_back_; }

  /// Chooses among the latest estimates at time `now_s`. An estimate is returned as new only once,
  /// and never with a stamp older than one already returned (the output stays in order even when
  /// the sources have different latencies).
  /// A clock jump back (see offer) resets the ordering state here too.
  Decision decide(double now_s);

  const ArbiterConfig& config() const { return config_; }
  /// Replaces the configuration (live tuning), keeping the sources' history and the regime.
  /// Throws std::invalid_argument, keeping the old one, when the new one is invalid.
  void reconfigure(const ArbiterConfig& config);
  RangeRegime regime() const { return regime_; }
  std::uint64_t rejectedCount() const { return rejected_; }
  const ConsistencyCounts& consistencyCounts() const { return counts_; }
  /// The latest accepted estimate of a source, if any.
  const std::optional<EstimateSummary>& latest(Source source) const;

 private:
  /// Empty when usable; otherwise why not ("stale 0.80 s", "no target: <status>", ...).
  std::string unusableReason(const EstimateSummary& e, double now_s) const;
  /// Empty when a mono estimate's quality is good enough; otherwise why not.
  std::string poorQualityReason(const EstimateSummary& e) const;
  void preferClaimedOrientation(std::array<Source, kSourceCount>* preference) const;
  void updateRegime(double range_m);

  // The cross-source consistency check.
  enum class Verdict : std::uint8_t { kFirst, kSecond, kUndecided };
  struct PairOutcome {
    Source other{Source::kDisparity};
    ConsistencyTest test;
    Verdict verdict{Verdict::kUndecided};
    Resolution resolution{Resolution::kNone};
  };
  struct CandidateCheck {
    std::optional<PairOutcome> lost;       ///< a contradiction the other source won
    std::optional<PairOutcome> undecided;  ///< a contradiction nothing decides
    std::vector<PairOutcome> outvoted;     ///< contradictions the candidate won
  };
  /// Tests candidate `c` against every other candidate and arbitrates each contradiction.
  CandidateCheck checkCandidate(Source c, const std::array<bool, kSourceCount>& candidate);
  /// The candidates in order of preference, each checked against the others; fills `decision`.
  void chooseConsistent(const std::array<std::string, kSourceCount>& why_not,
                        const std::array<Source, kSourceCount>& preference, std::string reason, Decision& decision);
  std::optional<ComparablePose> comparable(Source source) const;
  /// Tests two sources' latest estimates if both have a pose and their stamps are close enough.
  std::optional<ConsistencyTest> testPair(Source a, Source b, bool* first_time);
  /// Which of `first` and `second` (which disagree) the other evidence backs.
  PairOutcome arbitrate(Source first, Source second, const std::array<bool, kSourceCount>& candidate,
                        const ConsistencyTest& test);
  Verdict vote(const ComparablePose& judge, const ComparablePose& first, const ComparablePose& second) const;
  /// The newest published output older than `before_s` and not older than timeout_s before it.
  std::optional<ComparablePose> previousOutput(double before_s) const;
  void recordOutput(Source source);
  /// True the first time a given pair of estimates is seen (for the counts).
  bool firstTimeSeen(Source a, Source b);

  ArbiterConfig config_;
  std::array<std::optional<EstimateSummary>, kSourceCount> latest_{};
  RangeRegime regime_{RangeRegime::kUnknown};
  std::optional<double> last_output_stamp_s_;
  std::optional<Source> last_output_source_;
  std::uint64_t rejected_{0};
  docking_msgs::checks::ClockJumpDetector clock_;
  std::uint64_t clock_jumps_back_{0};
  /// Resets the ordering state when `now_s` shows the clock jumped back.
  void followClock(double now_s);
  std::deque<ComparablePose> outputs_;  ///< published outputs with a pose, newest last, within timeout_s
  /// Per unordered pair of sources: the stamps last counted.
  std::array<std::optional<std::pair<double, double>>, kSourceCount> counted_pairs_{};
  ConsistencyCounts counts_;
};

}  // namespace arbiter
}  // namespace docking_perception
