#include "docking_perception/arbiter/source_arbiter.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <stdexcept>

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

const char* decisionCodeName(DecisionCode code) {
  switch (code) {
    case DecisionCode::kChosen:
      return "chosen";
    case DecisionCode::kChosenOverDisagreement:
      return "chosen_over_disagreement";
    case DecisionCode::kNoUsableEstimate:
      return "no_usable_estimate";
    case DecisionCode::kSourcesDisagree:
      return "sources_disagree";
  }
  return "unknown";
}

const char* resolutionName(Resolution resolution) {
  switch (resolution) {
    case Resolution::kNone:
      return "none";
    case Resolution::kThirdSource:
      return "third source";
    case Resolution::kPreviousOutput:
      return "previous output";
  }
  return "unknown";
}

const char* offerProblemName(OfferProblem problem) {
  switch (problem) {
    case OfferProblem::kNone:
      return "none";
    case OfferProblem::kUnknownSource:
      return "unknown_source";
    case OfferProblem::kStampNotFinite:
      return "stamp_not_finite";
    case OfferProblem::kStampInFuture:
      return "stamp_in_future";
    case OfferProblem::kStampTooOld:
      return "stamp_too_old";
    case OfferProblem::kOutOfOrder:
      return "out_of_order";
    case OfferProblem::kStampUnset:
      return "stamp_unset";
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
  docking_settings::validateSettings(c);
  if (c.hysteresis_m >= c.switch_range_m) throw std::invalid_argument("hysteresis_m must be in [0, switch_range_m)");
}

SourceArbiter::SourceArbiter(const ArbiterConfig& config) : config_(config) { validate(config_); }

void SourceArbiter::reconfigure(const ArbiterConfig& config) {
  validate(config);
  config_ = config;
}

const std::optional<EstimateSummary>& SourceArbiter::latest(Source source) const {
  return latest_.at(indexOf(source));
}

void SourceArbiter::followClock(double now_s) {
  if (!clock_.jumpedBack(now_s)) return;
  ++clock_jumps_back_;
  resetOrdering();
}

void SourceArbiter::resetOrdering() {
  latest_ = {};
  last_output_stamp_s_.reset();
  last_output_source_.reset();
  outputs_.clear();
  counted_pairs_ = {};
}

OfferResult SourceArbiter::offer(const EstimateSummary& estimate, double now_s) {
  followClock(now_s);
  using docking_msgs::checks::StampProblem;
  const StampProblem stamp = docking_msgs::checks::checkStamp(estimate.stamp_s, now_s, docking_msgs::checks::kStampLimits);
  if (stamp == StampProblem::kNone) return offer(estimate);
  OfferResult result;
  ++rejected_;
  const double ahead = estimate.stamp_s - now_s;
  if (stamp == StampProblem::kNotFinite) {
    result.problem = OfferProblem::kStampNotFinite;
    result.reason = std::string(sourceName(estimate.source)) + ": stamp is not finite";
  } else if (stamp == StampProblem::kUnset) {
    result.problem = OfferProblem::kStampUnset;
    result.reason = std::string(sourceName(estimate.source)) + ": stamp is 0 (not set)";
  } else if (stamp == StampProblem::kFuture) {
    result.problem = OfferProblem::kStampInFuture;
    result.reason = std::string(sourceName(estimate.source)) + ": stamped " + formatDouble("%.3f", ahead) +
                    " s in the future (limit " + formatDouble("%.3f", docking_msgs::checks::kStampLimits.max_future_s) + " s)";
  } else {
    result.problem = OfferProblem::kStampTooOld;
    result.reason = std::string(sourceName(estimate.source)) + ": stamped " + formatDouble("%.3f", -ahead) +
                    " s in the past (limit " + formatDouble("%.3f", docking_msgs::checks::kStampLimits.max_age_s) + " s)";
  }
  return result;
}

OfferResult SourceArbiter::offer(const EstimateSummary& estimate) {
  OfferResult result;
  if (indexOf(estimate.source) >= kSourceCount) {
    ++rejected_;
    result.problem = OfferProblem::kUnknownSource;
    result.reason = "unknown source";
    return result;
  }
  if (!std::isfinite(estimate.stamp_s)) {
    ++rejected_;
    result.problem = OfferProblem::kStampNotFinite;
    result.reason = std::string(sourceName(estimate.source)) + ": stamp is not finite";
    return result;
  }
  auto& slot = latest_[indexOf(estimate.source)];
  if (slot && estimate.stamp_s <= slot->stamp_s) {
    ++rejected_;
    result.problem = OfferProblem::kOutOfOrder;
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

// A mono estimate may withhold its orientation (rotation sigma too large) and still give a position: it
// then ranks after the other mono source if that one claims an orientation, and before disparity.
void SourceArbiter::preferClaimedOrientation(std::array<Source, kSourceCount>* preference) const {
  auto claims = [this](Source s) {
    const auto& e = latest_[indexOf(s)];
    return e && e->orientation_valid;
  };
  auto first = std::find_if(preference->begin(), preference->end(), [](Source s) { return isMono(s); });
  auto second = std::find_if(first + 1, preference->end(), [](Source s) { return isMono(s); });
  if (second != preference->end() && !claims(*first) && claims(*second)) std::iter_swap(first, second);
}

std::string SourceArbiter::poorQualityReason(const EstimateSummary& e) const {
  if (!isMono(e.source)) return {};
  // An IR pose is made from its five LEDs or not at all: only the visible pose's inliers are counted.
  const auto min_inliers = static_cast<std::uint32_t>(config_.min_visible_inliers);
  if (e.source == Source::kMonoVisible && e.feature_inliers < min_inliers) {
    return "poor (" + std::to_string(e.feature_inliers) + " inliers < " + std::to_string(min_inliers) + ")";
  }
  // The estimator's own max_reprojection_px bounds the error of a valid pose; a second, lower limit here
  // changed no estimate of the held-out replay.
  if (!std::isfinite(e.reprojection_error_px)) return "poor (reprojection error not finite)";
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
  followClock(now_s);
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

  std::array<Source, kSourceCount> preference =
      regime_ == RangeRegime::kNear
          ? std::array<Source, kSourceCount>{Source::kMonoVisible, Source::kMonoIr, Source::kDisparity}
          : std::array<Source, kSourceCount>{Source::kDisparity, Source::kMonoVisible, Source::kMonoIr};
  preferClaimedOrientation(&preference);

  std::string reason = regimeName(regime_);
  if (range) reason += " (" + formatDouble("%.2f", *range) + " m)";
  chooseConsistent(why_not, preference, reason, decision);
  if (!decision.valid) return decision;

  // Publish each estimate once and keep the output in stamp order across sources.
  decision.is_new = !last_output_stamp_s_ || decision.stamp_s > *last_output_stamp_s_;
  if (decision.is_new) {
    last_output_stamp_s_ = decision.stamp_s;
    last_output_source_ = decision.source;
    recordOutput(decision.source);
  } else if (!last_output_source_ || *last_output_source_ != decision.source) {
    decision.reason += " (waiting for one newer than the last published)";
  }
  return decision;
}

// ---- Consistency across sources --------------------------------------------------------------
//
// Rule (README "arbiter", "Consistency"): the candidates are tried in order of preference. A
// candidate is tested against every other usable source whose stamp is within the tolerance (mono
// vs mono: position and orientation; with disparity: position). When one contradicts it, the other
// evidence decides: first the remaining source(s) (a vote: agrees with one, contradicts the other),
// then the newest previous output older than both. The candidate is used when it wins every
// contradiction, skipped when it loses one (the next candidate is tried, with it left out), and
// nothing is published (kSourcesDisagree) when a contradiction cannot be decided.

std::optional<ComparablePose> SourceArbiter::comparable(Source source) const {
  const auto& e = latest_[indexOf(source)];
  if (!e || !e->pose) return std::nullopt;
  ComparablePose c;
  c.stamp_s = e->stamp_s;
  c.pose = *e->pose;
  c.has_orientation = isMono(source) && e->orientation_valid;
  if (e->twist) {
    const double speed = e->twist->linear.norm();
    const double rate = e->twist->angular.norm();
    c.speed_mps = std::isfinite(speed) ? speed : 0.0;
    c.rate_radps = std::isfinite(rate) ? rate : 0.0;
  }
  return c;
}

bool SourceArbiter::firstTimeSeen(Source a, Source b) {
  if (indexOf(a) > indexOf(b)) std::swap(a, b);
  const std::size_t pair = indexOf(a) + indexOf(b) - 1;  // (0,1) -> 0, (0,2) -> 1, (1,2) -> 2
  const std::pair<double, double> stamps{latest_[indexOf(a)]->stamp_s, latest_[indexOf(b)]->stamp_s};
  if (counted_pairs_[pair] && *counted_pairs_[pair] == stamps) return false;
  counted_pairs_[pair] = stamps;
  return true;
}

std::optional<ConsistencyTest> SourceArbiter::testPair(Source a, Source b, bool* first_time) {
  const auto pose_a = comparable(a);
  const auto pose_b = comparable(b);
  if (!pose_a || !pose_b) return std::nullopt;
  if (std::abs(pose_a->stamp_s - pose_b->stamp_s) > config_.consistency.stamp_tolerance_s) return std::nullopt;
  const auto test = compare(*pose_a, *pose_b, config_.consistency);
  if (!test) return std::nullopt;
  *first_time = firstTimeSeen(a, b);
  if (*first_time) {
    ++counts_.comparisons;
    if (!test->agree) ++counts_.disagreements;
  }
  return test;
}

SourceArbiter::Verdict SourceArbiter::vote(const ComparablePose& judge, const ComparablePose& first,
                                           const ComparablePose& second) const {
  const auto with_first = compare(judge, first, config_.consistency);
  const auto with_second = compare(judge, second, config_.consistency);
  if (!with_first || !with_second || with_first->agree == with_second->agree) return Verdict::kUndecided;
  return with_first->agree ? Verdict::kFirst : Verdict::kSecond;
}

SourceArbiter::PairOutcome SourceArbiter::arbitrate(Source first, Source second,
                                                    const std::array<bool, kSourceCount>& candidate,
                                                    const ConsistencyTest& test) {
  PairOutcome outcome;
  outcome.other = second;
  outcome.test = test;
  const ComparablePose a = *comparable(first);
  const ComparablePose b = *comparable(second);

  int for_first = 0;
  int for_second = 0;
  for (std::size_t i = 0; i < kSourceCount; ++i) {
    const Source judge_source = static_cast<Source>(i);
    if (judge_source == first || judge_source == second || !candidate[i]) continue;
    const auto judge = comparable(judge_source);
    const double tolerance = config_.consistency.stamp_tolerance_s;
    if (!judge || std::abs(judge->stamp_s - a.stamp_s) > tolerance || std::abs(judge->stamp_s - b.stamp_s) > tolerance) {
      continue;
    }
    const Verdict v = vote(*judge, a, b);
    for_first += v == Verdict::kFirst;
    for_second += v == Verdict::kSecond;
  }
  if (for_first != for_second) {
    outcome.verdict = for_first > for_second ? Verdict::kFirst : Verdict::kSecond;
    outcome.resolution = Resolution::kThirdSource;
    return outcome;
  }
  if (const auto previous = previousOutput(std::min(a.stamp_s, b.stamp_s))) {
    outcome.verdict = vote(*previous, a, b);
    if (outcome.verdict != Verdict::kUndecided) outcome.resolution = Resolution::kPreviousOutput;
  }
  return outcome;
}

std::optional<ComparablePose> SourceArbiter::previousOutput(double before_s) const {
  for (auto it = outputs_.rbegin(); it != outputs_.rend(); ++it) {
    if (it->stamp_s >= before_s) continue;
    if (before_s - it->stamp_s > config_.timeout_s) break;
    return *it;
  }
  return std::nullopt;
}

void SourceArbiter::recordOutput(Source source) {
  const auto output = comparable(source);
  if (!output) return;
  outputs_.push_back(*output);
  while (!outputs_.empty() && output->stamp_s - outputs_.front().stamp_s > config_.timeout_s) outputs_.pop_front();
}

namespace {

std::string describeTest(const ConsistencyTest& test) {
  return "chi2 " + formatDouble("%.1f", test.chi2) + " > " + formatDouble("%.1f", test.gate) + ", " +
         std::to_string(test.dof) + " dof, " + formatDouble("%.3f", test.dt_s) + " s apart";
}

}  // namespace

SourceArbiter::CandidateCheck SourceArbiter::checkCandidate(Source c, const std::array<bool, kSourceCount>& candidate) {
  CandidateCheck check;
  for (std::size_t si = 0; config_.consistency.enabled && si < kSourceCount; ++si) {
    const Source s = static_cast<Source>(si);
    if (s == c || !candidate[si]) continue;
    bool first_time = false;
    const auto test = testPair(c, s, &first_time);
    if (!test || test->agree) continue;
    const PairOutcome outcome = arbitrate(c, s, candidate, *test);
    if (first_time) {
      if (outcome.resolution == Resolution::kThirdSource) ++counts_.resolved_by_third_source;
      if (outcome.resolution == Resolution::kPreviousOutput) ++counts_.resolved_by_previous_output;
      if (outcome.verdict == Verdict::kUndecided) ++counts_.undecided;
    }
    if (outcome.verdict == Verdict::kSecond && !check.lost) check.lost = outcome;
    if (outcome.verdict == Verdict::kUndecided && !check.undecided) check.undecided = outcome;
    if (outcome.verdict == Verdict::kFirst) check.outvoted.push_back(outcome);
  }
  return check;
}

void SourceArbiter::chooseConsistent(const std::array<std::string, kSourceCount>& why_not,
                                     const std::array<Source, kSourceCount>& preference, std::string reason,
                                     Decision& decision) {
  std::array<bool, kSourceCount> candidate{};
  bool any_usable = false;
  for (std::size_t i = 0; i < kSourceCount; ++i) {
    candidate[i] = why_not[i].empty();
    any_usable = any_usable || candidate[i];
  }
  for (Source c : preference) {
    const std::size_t ci = indexOf(c);
    if (!candidate[ci]) {
      if (!decision.inconsistent[ci]) reason += std::string(": ") + sourceName(c) + " " + why_not[ci];
      continue;
    }
    const CandidateCheck check = checkCandidate(c, candidate);
    if (check.lost) {  // another source is better supported: try the next candidate without this one
      candidate[ci] = false;
      decision.inconsistent[ci] = true;
      decision.resolution = check.lost->resolution;
      reason += std::string(": ") + sourceName(c) + " contradicts " + sourceName(check.lost->other) + " (" +
                describeTest(check.lost->test) + "), which the " + resolutionName(check.lost->resolution) +
                " backs";
      continue;
    }
    if (check.undecided) {
      decision.valid = false;
      decision.code = DecisionCode::kSourcesDisagree;
      decision.inconsistent[ci] = true;
      decision.inconsistent[indexOf(check.undecided->other)] = true;
      decision.reason = "sources disagree; " + reason + ": " + sourceName(c) + " contradicts " +
                        sourceName(check.undecided->other) + " (" + describeTest(check.undecided->test) +
                        ") and nothing decides which is right";
      return;
    }
    std::string outvoted;
    for (const PairOutcome& o : check.outvoted) {
      decision.inconsistent[indexOf(o.other)] = true;
      decision.resolution = o.resolution;
      outvoted += std::string(", ") + sourceName(o.other) + " outvoted by the " + resolutionName(o.resolution) +
                  " (" + describeTest(o.test) + ")";
    }
    decision.valid = true;
    decision.source = c;
    decision.stamp_s = latest_[ci]->stamp_s;
    const bool any_inconsistent =
        std::find(decision.inconsistent.begin(), decision.inconsistent.end(), true) != decision.inconsistent.end();
    decision.code = any_inconsistent ? DecisionCode::kChosenOverDisagreement : DecisionCode::kChosen;
    decision.reason = reason + ": using " + sourceName(c) + outvoted;
    return;
  }
  decision.valid = false;
  decision.code = any_usable ? DecisionCode::kSourcesDisagree : DecisionCode::kNoUsableEstimate;
  decision.reason = "no usable estimate; " + reason;
}

}  // namespace arbiter
}  // namespace docking_perception
