#include "docking_planner/docking_planner.h"

#include <cmath>
#include <cstdio>
#include <stdexcept>

namespace docking_planner {
namespace {

std::string fmt(const char* format, double value) {
  char buffer[96];
  std::snprintf(buffer, sizeof(buffer), format, value);
  return buffer;
}

std::string fmt2(const char* format, double a, double b) {
  char buffer[128];
  std::snprintf(buffer, sizeof(buffer), format, a, b);
  return buffer;
}

bool finite(const ChaserOdometry& o) {
  return std::isfinite(o.stamp_s) && std::isfinite(o.pose.x) && std::isfinite(o.pose.y) &&
         std::isfinite(o.pose.yaw) && std::isfinite(o.twist.vx) && std::isfinite(o.twist.vy) &&
         std::isfinite(o.twist.wz);
}

constexpr double kRadToDeg = 180.0 / M_PI;
// ALIGN: off the safe circle by more than this many circle tolerances, back to APPROACH.
constexpr double kOffCircleTolerances = 4.0;
// Orbit without a known port axis: the axis is placed this far ahead, so the ALIGN law moves the chaser
// along the circle (counter-clockwise seen from above) at its speed limit.
constexpr double kOrbitLeadRad = 0.5;

// A port whose orientation is unknown, taken as facing the chaser and not turning: the approach goal is
// then the point of the safe circle on the line of sight, and no rotation is fed forward.
void takeAsFacingTheChaser(const Pose2D& chaser, PortState* port) {
  port->pose.yaw = std::atan2(chaser.y - port->pose.y, chaser.x - port->pose.x);
  port->yaw_rate = 0.0;
}

}  // namespace

const char* stateName(DockingPhase state) {
  switch (state) {
    case DockingPhase::kSearch:
      return "SEARCH";
    case DockingPhase::kApproach:
      return "APPROACH";
    case DockingPhase::kAlign:
      return "ALIGN";
    case DockingPhase::kFinal:
      return "FINAL";
    case DockingPhase::kDocked:
      return "DOCKED";
    case DockingPhase::kHold:
      return "HOLD";
    case DockingPhase::kAbort:
      return "ABORT";
    case DockingPhase::kIdle:
      return "IDLE";
  }
  return "UNKNOWN";
}

const char* outcomeName(DockingOutcome outcome) {
  switch (outcome) {
    case DockingOutcome::kDocked:
      return "DOCKED";
    case DockingOutcome::kCancelled:
      return "CANCELLED";
    case DockingOutcome::kTimeBudget:
      return "TIME_BUDGET";
    case DockingOutcome::kTargetLost:
      return "TARGET_LOST";
    case DockingOutcome::kClientGone:
      return "CLIENT_GONE";
    case DockingOutcome::kRejected:
      return "REJECTED";
    case DockingOutcome::kShutdown:
      return "SHUTDOWN";
    case DockingOutcome::kPerceptionLost:
      return "PERCEPTION_LOST";
  }
  return "UNKNOWN";
}

std::string checkLimits(const DockingLimits& limits) {
  const auto usable = [](double v) { return std::isfinite(v) && v >= 0.0; };
  if (!usable(limits.time_budget_s)) return "time_budget_s must be a number >= 0 (0: no limit)";
  if (!usable(limits.search_timeout_s)) return "search_timeout_s must be a number >= 0 (0: the planner's)";
  if (!usable(limits.max_speed_mps)) return "max_speed_mps must be a number >= 0 (0: the planner's)";
  return "";
}

void validate(const PlannerConfig& c) {
  docking_settings::validateSettings(c);
  validate(c.law);
  if (std::abs(c.search_yaw_rate_radps) > c.law.max_yaw_rate_radps) {
    throw std::invalid_argument("search_yaw_rate_radps must be within max_yaw_rate_radps");
  }
  if (c.final_abort_lateral_m <= c.align_lateral_tolerance_m || c.final_abort_yaw_rad <= c.align_yaw_tolerance_rad) {
    throw std::invalid_argument(
        "final_abort_lateral_m / final_abort_yaw_rad must exceed align_lateral_tolerance_m / align_yaw_tolerance_rad");
  }
  if (c.odometry_only_range_m > c.blind_final_range_m) {
    throw std::invalid_argument("odometry_only_range_m must be in [0, blind_final_range_m]");
  }
  if (c.search_orbit_radius_m < c.law.safe_radius_m) {
    throw std::invalid_argument("search_orbit_radius_m must be a number >= safe_radius_m");
  }
  if (c.orientation_timeout_s < c.max_blind_s) {
    throw std::invalid_argument("orientation_timeout_s must be >= max_blind_s (the blind finish needs the port axis)");
  }
}

namespace {
ApproachConfig orbitLaw(const PlannerConfig& c) {
  ApproachConfig law = c.law;
  law.safe_radius_m = c.search_orbit_radius_m;
  law.align_speed_mps = c.orbit_speed_mps;
  return law;
}
}  // namespace

DockingPlanner::DockingPlanner(const PlannerConfig& config, double probe_x_m)
    : config_((validate(config), config)),
      law_(config.law, probe_x_m),
      orbit_law_(orbitLaw(config), probe_x_m),
      track_(config.track) {}

void DockingPlanner::reset(double now_s) {
  track_.reset();
  last_seen_s_ = -1e300;
  last_rejection_.clear();
  nan_estimate_ = false;
  last_tip_error_m_ = 1e9;
  enter(DockingPhase::kIdle, now_s, "reset: target forgotten; waiting for a docking goal");
}

void DockingPlanner::forgetTarget(double now_s) {
  track_.reset();
  last_seen_s_ = -1e300;
  last_rejection_.clear();
  nan_estimate_ = false;
  last_tip_error_m_ = 1e9;
  state_since_s_ = now_s;
  started_s_ = now_s;
}

bool DockingPlanner::start(double now_s, const DockingLimits& limits, std::string* why_not) {
  std::string problem = checkLimits(limits);
  if (problem.empty() && active()) problem = std::string("a docking is already running (") + stateName(state_) + ")";
  if (problem.empty() && !std::isfinite(now_s)) problem = "planner time is not finite";
  if (!problem.empty()) {
    if (why_not) *why_not = problem;
    return false;
  }
  limits_ = limits;
  started_s_ = now_s;
  last_tip_error_m_ = 1e9;
  enter(DockingPhase::kSearch, now_s, "docking started");
  return true;
}

void DockingPlanner::cancel(double now_s, const std::string& reason) {
  if (active()) enter(DockingPhase::kIdle, now_s, reason);
}

void DockingPlanner::scaleToSpeedCap(BodyTwist* command) const {
  if (limits_.max_speed_mps <= 0.0) return;
  const double speed = std::hypot(command->vx, command->vy);
  if (speed > limits_.max_speed_mps) {
    command->vx *= limits_.max_speed_mps / speed;
    command->vy *= limits_.max_speed_mps / speed;
  }
}

void DockingPlanner::enter(DockingPhase state, double now_s, const std::string& reason) {
  state_ = state;
  state_reason_ = reason;
  state_since_s_ = now_s;
  min_goal_distance_m_ = INFINITY;
}

TrackUpdate DockingPlanner::addObservation(const TargetObservation& observation) {
  if (state_ == DockingPhase::kFinal && last_tip_error_m_ < config_.odometry_only_range_m) {
    // Near contact the cameras see only part of the target: finish on the pose held in odom, unless a
    // full pose (the inner pattern) agrees with it closely enough to be the port and not a partial view.
    const std::string why_not = contactEstimateRejection(observation);
    if (!why_not.empty()) return TrackUpdate{false, why_not};
  }
  if (config_.position_only_gate_m > 0.0 && observation.valid && !observation.orientation_valid &&
      track_.hasPosition() && std::isfinite(observation.stamp_s) &&
      observation.stamp_s - track_.lastStamp() < config_.hold_timeout_s) {
    const Vec2 held = track_.predict(observation.stamp_s).pose.position();
    const double off = (observation.pose.position() - held).norm();
    if (std::isfinite(off) && off > config_.position_only_gate_m) {
      // Another object of the scene (the stereo detector picks the best blob): not the target.
      TrackUpdate rejected{false, fmt("position-only estimate %.2f m from the held target: not used", off)};
      last_rejection_ = rejected.reason;
      return rejected;
    }
  }
  if (observation.valid && !observation.orientation_valid && track_.hasOrientation() &&
      std::isfinite(observation.stamp_s) && std::isfinite(observation.pose.x) && std::isfinite(observation.pose.y) &&
      observation.stamp_s - track_.lastOrientationStamp() <= config_.orientation_timeout_s) {
    // The target is there, but the stereo blob's centre is not the port: keep the held port pose.
    last_seen_s_ = std::max(last_seen_s_, observation.stamp_s);
    last_rejection_.clear();
    nan_estimate_ = false;
    return TrackUpdate{true, "position-only estimate: target seen, the port pose held from the poses"};
  }
  TrackUpdate result = track_.update(observation);
  if (result.accepted) {
    last_seen_s_ = std::max(last_seen_s_, observation.stamp_s);
    last_rejection_.clear();
    nan_estimate_ = false;
  } else {
    last_rejection_ = result.reason;
    if (observation.valid && result.not_finite) nan_estimate_ = true;
  }
  return result;
}

std::string DockingPlanner::contactEstimateRejection(const TargetObservation& observation) const {
  if (config_.contact_estimate_gate_m <= 0.0 || config_.contact_estimate_gate_yaw_rad <= 0.0) {
    return "inside the odometry-only range: estimate not used";
  }
  if (!observation.valid || !observation.orientation_valid) {
    return "inside the odometry-only range: only full poses are used";
  }
  if (!track_.hasOrientation() || !std::isfinite(observation.stamp_s) || !std::isfinite(observation.pose.x) ||
      !std::isfinite(observation.pose.y) || !std::isfinite(observation.pose.yaw)) {
    return "inside the odometry-only range: no held port pose to check the estimate against";
  }
  const Pose2D held = track_.predict(observation.stamp_s).pose;
  const double off_m = (observation.pose.position() - held.position()).norm();
  const double off_yaw = std::abs(wrapAngle(observation.pose.yaw - held.yaw));
  // The gates widen by 3 sigma of the estimate's own uncertainty (when it gives one): a pose that says
  // it is coarse (the inner pattern's yaw at 0.2-0.3 m, several degrees) is weighted by the track, not
  // refused; a confident one that is far off is a jump.
  const double position_gate = config_.contact_estimate_gate_m + 3.0 * std::max(0.0, observation.position_sigma_m);
  const double yaw_gate = config_.contact_estimate_gate_yaw_rad + 3.0 * std::max(0.0, observation.yaw_sigma_rad);
  if (!(off_m <= position_gate) || !(off_yaw <= yaw_gate)) {
    return fmt2("inside the odometry-only range: estimate %.1f mm / %.2f deg from the held port, not used",
                off_m * 1000.0, off_yaw * 180.0 / M_PI);
  }
  return "";
}

double DockingPlanner::searchTimeout() const {
  return limits_.search_timeout_s > 0.0 ? limits_.search_timeout_s : kDefaultSearchTimeoutS;
}

bool DockingPlanner::targetVisible(double now_s) const {
  if (nan_estimate_ || !track_.hasPosition()) return false;
  const double age = now_s - last_seen_s_;
  return age <= config_.estimate_timeout_s && age >= -config_.estimate_timeout_s;
}

std::string DockingPlanner::lostReason(double now_s) const {
  if (nan_estimate_) return "latest estimate contains NaN";
  std::string reason = track_.hasPosition() ? fmt("target not seen for %.1f s", now_s - last_seen_s_)
                                            : std::string("no target estimate yet");
  if (!last_rejection_.empty()) reason += " (" + last_rejection_ + ")";
  return reason;
}

void DockingPlanner::notePerception(double now_s, bool sources_silent) {
  if (!std::isfinite(now_s)) return;
  last_perception_s_ = now_s;
  sources_silent_ = sources_silent;
}

std::string DockingPlanner::perceptionProblem(double now_s) const {
  const std::string inputs = input_problem_.empty() ? "" : "; " + input_problem_;
  if (sources_silent_) return "perception silent: no estimator publishes (stalled or gone)" + inputs;
  const double age = now_s - last_perception_s_;
  if (age >= 0.0 && age <= config_.input_timeout_s) return "";
  if (last_perception_s_ < -1e299) return "perception silent: no target estimate message yet" + inputs;
  if (age < 0.0) return "";  // the clock went back (a bag looped): the next message decides
  return fmt("perception silent: no target estimate message for %.1f s", age) + inputs;
}

PlannerOutput DockingPlanner::stop(PlannerOutput out, const std::string& reason) const {
  out.command = BodyTwist{};
  out.reason = reason;
  return out;
}

PlannerOutput DockingPlanner::orbitForTheFace(PlannerOutput out, const Pose2D& chaser, PortState port,
                                              const std::string& why) const {
  takeAsFacingTheChaser(chaser, &port);  // position only
  const double r_orbit = config_.search_orbit_radius_m;
  const double range_m = (port.pose.position() - chaser.position()).norm();
  if (range_m > r_orbit + 4.0 * config_.circle_tolerance_m) {
    const LawCommand to_orbit = orbit_law_.command(Phase::kApproach, chaser, port);
    out.command = to_orbit.twist;
    out.goal_distance_m = to_orbit.goal_distance_m;
    out.goal = to_orbit.goal;
    out.path = orbit_law_.plannedPath(Phase::kApproach, chaser, port.pose);
    out.reason = why + fmt("approaching on position only (port orientation unknown) to %.2f m", r_orbit);
    return out;
  }
  // The ALIGN law around an axis kept a fixed angle ahead of the chaser moves it along the orbit; the
  // heading points the cameras at the target (the law's would keep it at the edge of the view).
  PortState lead = port;
  lead.pose.yaw = wrapAngle(port.pose.yaw + kOrbitLeadRad);
  const LawCommand cmd = orbit_law_.command(Phase::kAlign, chaser, lead);
  const double line_of_sight = std::atan2(port.pose.y - chaser.y, port.pose.x - chaser.x);
  const double orbit_rate = range_m > 1e-3 ? config_.orbit_speed_mps / range_m : 0.0;
  out.command = cmd.twist;
  out.command.wz = clampAbs(orbit_rate + config_.law.correction_gain * wrapAngle(line_of_sight - chaser.yaw),
                            config_.law.max_yaw_rate_radps);
  out.goal_distance_m = cmd.goal_distance_m;
  out.goal = cmd.goal;
  out.path = orbit_law_.plannedPath(Phase::kAlign, chaser, lead.pose);
  out.reason = why + fmt("orbiting the target at %.2f m to find the port face", r_orbit);
  return out;
}

// One cycle: what the inputs say now, whether they let the chaser move at all, then the state machine.
PlannerOutput DockingPlanner::update(double now_s, const std::optional<ChaserOdometry>& odometry) {
  if (!std::isfinite(now_s)) {
    PlannerOutput out;
    out.state = state_;
    return stop(out, "planner time is not finite");
  }
  if (!state_since_s_) state_since_s_ = now_s;
  Cycle cycle = observe(now_s, odometry);
  if (std::optional<PlannerOutput> stopped = checkInputs(cycle)) return *stopped;
  return runStateMachine(cycle);
}

std::string DockingPlanner::odometryProblem(double now_s, const std::optional<ChaserOdometry>& odometry) const {
  if (!odometry) return "no odometry yet";
  if (!finite(*odometry)) return "odometry contains NaN or infinity";
  if (now_s - odometry->stamp_s > config_.input_timeout_s) {
    return fmt("odometry stale (%.2f s old)", now_s - odometry->stamp_s);
  }
  return "";
}

DockingPlanner::Cycle DockingPlanner::observe(double now_s, const std::optional<ChaserOdometry>& odometry) {
  Cycle c;
  c.now_s = now_s;
  c.odom_problem = odometryProblem(now_s, odometry);
  const bool odometry_ok = c.odom_problem.empty();
  const bool visible = targetVisible(now_s);
  c.orientation_known =
      track_.hasOrientation() && now_s - track_.lastOrientationStamp() <= config_.orientation_timeout_s;
  if (track_.hasPosition()) c.port = track_.predict(now_s);
  if (odometry_ok) c.chaser = odometry->pose;
  if (track_.hasPosition() && odometry_ok && !c.orientation_known) {
    takeAsFacingTheChaser(c.chaser, &c.port);  // position only (far away, disparity)
  }
  PlannerOutput& out = c.out;
  out.has_target = track_.hasPosition() && odometry_ok;
  if (out.has_target) {
    out.geometry = law_.measure(c.chaser, c.port.pose);
    out.port = c.port;
    out.port_orientation_known = c.orientation_known;
    last_tip_error_m_ = out.geometry.tip_error_m;
  }
  out.target_visible = visible && odometry_ok;
  out.estimate_source = track_.lastSource();
  return c;
}

bool DockingPlanner::moving(DockingPhase s) {
  return s == DockingPhase::kApproach || s == DockingPhase::kAlign || s == DockingPhase::kFinal ||
         s == DockingPhase::kAbort;
}

PlannerOutput DockingPlanner::finish(const Cycle& c, PlannerOutput o) const {
  o.state = state_;
  o.time_in_state_s = c.now_s - *state_since_s_;
  scaleToSpeedCap(&o.command);
  return o;
}

// The docking ends by itself: the outcome is reported in this cycle's output, IDLE from the next.
PlannerOutput DockingPlanner::endDocking(const Cycle& c, PlannerOutput o, DockingOutcome outcome,
                                         const std::string& reason) {
  o = finish(c, stop(o, reason));
  o.outcome = outcome;
  enter(DockingPhase::kIdle, c.now_s, reason);
  return o;
}

PlannerOutput DockingPlanner::drive(const Cycle& c, PlannerOutput o, Phase phase, const std::string& reason) const {
  const LawCommand cmd = law_.command(phase, c.chaser, c.port);
  o.command = cmd.twist;
  o.goal_distance_m = cmd.goal_distance_m;
  o.goal = cmd.goal;
  o.path = law_.plannedPath(phase, c.chaser, c.port.pose);
  o.reason = reason + (cmd.fov_limited ? " (heading held at the edge of the camera's view)" : "");
  return o;
}

// Stops the chaser for this cycle when no docking runs, its time budget is spent, the odometry is bad or
// perception is gone; otherwise nothing (a NaN estimate only sends a moving docking to HOLD).
std::optional<PlannerOutput> DockingPlanner::checkInputs(Cycle& c) {
  if (state_ == DockingPhase::kIdle) return finish(c, stop(c.out, state_reason_));
  if (limits_.time_budget_s > 0.0 && c.now_s - started_s_ > limits_.time_budget_s) {
    return endDocking(c, c.out, DockingOutcome::kTimeBudget,
                      fmt("time budget of %.1f s spent", limits_.time_budget_s) + " in " + stateName(state_));
  }
  if (!c.odom_problem.empty()) {
    if (moving(state_)) {
      resume_state_ = state_;
      enter(DockingPhase::kHold, c.now_s, c.odom_problem);
    }
    return finish(c, stop(c.out, c.odom_problem));
  }
  if (std::optional<PlannerOutput> held = holdWhilePerceptionGone(c)) return held;
  if (nan_estimate_ && moving(state_)) {
    resume_state_ = state_;
    enter(DockingPhase::kHold, c.now_s, "latest estimate contains NaN");
  }
  return std::nullopt;
}

// Perception gone: stop and wait, without the hold's timeout (searching or backing off needs eyes). Not
// for ever: after the search timeout the docking ends, saying what is missing.
std::optional<PlannerOutput> DockingPlanner::holdWhilePerceptionGone(Cycle& c) {
  std::string problem = perceptionProblem(c.now_s);
  if (problem.empty() && !input_problem_.empty() && !c.out.target_visible) {
    problem = "target not seen with a camera at fault: " + input_problem_;
  }
  if (problem.empty()) {
    if (perception_down_) {
      perception_down_ = false;
      // The hold's timeout runs from the moment perception is back.
      if (state_ == DockingPhase::kHold) enter(DockingPhase::kHold, c.now_s, "perception back: holding for the target");
    }
    return std::nullopt;
  }
  if (!perception_down_) perception_down_since_s_ = c.now_s;
  perception_down_ = true;
  const double limit_s = searchTimeout();
  if (c.now_s - perception_down_since_s_ > limit_s) {
    return endDocking(c, c.out, DockingOutcome::kPerceptionLost,
                      fmt("no usable estimate for %.0f s: ", limit_s) + problem);
  }
  if (state_ != DockingPhase::kHold && state_ != DockingPhase::kDocked) {
    resume_state_ = state_;
    enter(DockingPhase::kHold, c.now_s, problem);
  }
  return finish(c, stop(c.out, "holding: " + problem));
}

// A transition re-evaluates the new state in the same cycle, so that no cycle is lost; the state graph
// has no loop that can be taken without time passing, the bound is only a guard.
PlannerOutput DockingPlanner::runStateMachine(Cycle& c) {
  for (int pass = 0; pass < 6; ++pass) {
    if (std::optional<PlannerOutput> done = stepState(c)) return *done;
  }
  return finish(c, stop(c.out, "state machine did not settle: " + state_reason_));
}

// The current state's step: its output, or nothing when it moved to another state.
std::optional<PlannerOutput> DockingPlanner::stepState(Cycle& c) {
  switch (state_) {
    case DockingPhase::kIdle:
      return finish(c, stop(c.out, state_reason_));
    case DockingPhase::kDocked:
      return endDocking(c, c.out, DockingOutcome::kDocked, state_reason_);
    case DockingPhase::kSearch:
      return stepSearch(c);
    case DockingPhase::kHold:
      return stepHold(c);
    case DockingPhase::kAbort:
      return stepAbort(c);
    case DockingPhase::kApproach:
    case DockingPhase::kAlign:
    case DockingPhase::kFinal:
      return stepMoving(c);
  }
  return finish(c, stop(c.out, "unknown state"));
}

std::optional<PlannerOutput> DockingPlanner::stepSearch(Cycle& c) {
  PlannerOutput& out = c.out;
  const double in_state_s = c.now_s - *state_since_s_;
  if (out.target_visible) {
    enter(DockingPhase::kApproach, c.now_s, "target found");
    return std::nullopt;
  }
  const double search_timeout_s = searchTimeout();
  if (in_state_s > search_timeout_s) {
    return endDocking(c, out, DockingOutcome::kTargetLost,
                      fmt("no target for %.0f s of search", search_timeout_s) + " (" + lostReason(c.now_s) + ")");
  }
  if (in_state_s < kSearchWaitS) return finish(c, stop(out, lostReason(c.now_s) + ": waiting"));
  if (out.has_target && c.now_s - last_seen_s_ <= config_.search_orbit_memory_s) {
    // Seen not long ago: it is most likely still there with its face turned away (a turning target), or
    // just outside the view. Turning in place would look away from it 5 s in 6; orbiting where it was
    // keeps it in view and brings the face round.
    return finish(c, orbitForTheFace(out, c.chaser, c.port, lostReason(c.now_s) + ": looking where it was; "));
  }
  out.command = BodyTwist{0.0, 0.0, config_.search_yaw_rate_radps};
  out.reason = lostReason(c.now_s) + ": turning to look for it";
  return finish(c, out);
}

std::optional<PlannerOutput> DockingPlanner::stepHold(Cycle& c) {
  const double in_state_s = c.now_s - *state_since_s_;
  if (c.out.target_visible) {
    enter(resume_state_, c.now_s, "target back after a hold");
    return std::nullopt;
  }
  if (in_state_s > config_.hold_timeout_s) {
    if (c.out.has_target && c.out.geometry.range_m < config_.law.safe_radius_m - config_.circle_tolerance_m) {
      enter(DockingPhase::kAbort, c.now_s, lostReason(c.now_s) + ": backing off to the safe circle");
    } else {
      enter(DockingPhase::kSearch, c.now_s, lostReason(c.now_s));
    }
    return std::nullopt;
  }
  return finish(c, stop(c.out, "holding: " + lostReason(c.now_s)));
}

std::optional<PlannerOutput> DockingPlanner::stepAbort(Cycle& c) {
  const double in_state_s = c.now_s - *state_since_s_;
  if (!c.out.has_target) {
    enter(DockingPhase::kSearch, c.now_s, "abort: no target pose held");
    return std::nullopt;
  }
  // ABORT lasts at least one cycle (zero velocity outside the circle), so that it is published.
  if (in_state_s > 0.0 && c.out.geometry.range_m >= config_.law.safe_radius_m - config_.circle_tolerance_m) {
    enter(DockingPhase::kSearch, c.now_s, "backed off to the safe circle after: " + state_reason_);
    return std::nullopt;
  }
  if (in_state_s > kAbortTimeoutS) {
    enter(DockingPhase::kSearch, c.now_s, "backing off took too long");
    return std::nullopt;
  }
  return finish(c, drive(c, c.out, Phase::kBackOff, "abort: " + state_reason_));
}

// APPROACH, ALIGN, FINAL: with the target in view, or FINAL near contact on the pose held in odom.
std::optional<PlannerOutput> DockingPlanner::stepMoving(Cycle& c) {
  std::string blind_reason;
  if (!c.out.target_visible && !continueOnOdometry(c, &blind_reason)) return std::nullopt;
  c.out.on_odometry = !c.out.target_visible;
  if (state_ == DockingPhase::kApproach) return stepApproach(c);
  if (state_ == DockingPhase::kAlign) return stepAlign(c);
  return stepFinal(c, blind_reason);
}

// The target not seen while moving: FINAL near contact goes on, on odometry (true, with why in `reason`);
// otherwise HOLD, or ABORT when on odometry too long (false: another state).
bool DockingPlanner::continueOnOdometry(const Cycle& c, std::string* reason) {
  const ApproachGeometry& g = c.out.geometry;
  const double blind_s = c.now_s - track_.lastStamp();
  const bool near_contact = c.out.has_target && g.tip_error_m < config_.blind_final_range_m;
  if (state_ == DockingPhase::kFinal && near_contact && c.orientation_known && !nan_estimate_) {
    if (blind_s > config_.max_blind_s) {
      enter(DockingPhase::kAbort, c.now_s, fmt("final approach on odometry for too long (%.1f s)", blind_s));
      return false;
    }
    *reason = g.tip_error_m < config_.odometry_only_range_m
                  ? fmt("on odometry: probe tip within %.2f m, estimates no longer used", config_.odometry_only_range_m)
                  : fmt("on odometry: target not seen for %.1f s, pose held in odom", blind_s);
    return true;
  }
  resume_state_ = state_;
  enter(DockingPhase::kHold, c.now_s, lostReason(c.now_s));
  return false;
}

std::optional<PlannerOutput> DockingPlanner::stepApproach(Cycle& c) {
  // Position only (stereo far away, or the face turned away): go to the search orbit, not to the safe
  // circle (the stereo detector does not see the target well inside it), and orbit there, always the
  // same way (counter-clockwise), until a camera sees the face.
  if (!c.orientation_known) return finish(c, orbitForTheFace(c.out, c.chaser, c.port, ""));
  const LawCommand cmd = law_.command(Phase::kApproach, c.chaser, c.port);
  if (cmd.goal_distance_m < config_.circle_tolerance_m) {
    enter(DockingPhase::kAlign, c.now_s,
          fmt("on the safe circle, %.0f deg off the port axis", c.out.geometry.polar_angle_rad * kRadToDeg));
    return std::nullopt;
  }
  if (cmd.goal_distance_m > min_goal_distance_m_ + config_.divergence_margin_m) {
    enter(DockingPhase::kAbort, c.now_s,
          fmt2("approach diverging: goal %.2f m away, was %.2f m", cmd.goal_distance_m, min_goal_distance_m_));
    return std::nullopt;
  }
  min_goal_distance_m_ = std::min(min_goal_distance_m_, cmd.goal_distance_m);
  return finish(c, drive(c, c.out, Phase::kApproach, "straight to the safe circle"));
}

std::optional<PlannerOutput> DockingPlanner::stepAlign(Cycle& c) {
  const ApproachGeometry& g = c.out.geometry;
  const double r_safe = config_.law.safe_radius_m;
  const double arc_m = std::abs(g.polar_angle_rad) * r_safe;
  if (arc_m < config_.align_lateral_tolerance_m && std::abs(g.yaw_error_rad) < config_.align_yaw_tolerance_rad &&
      std::abs(g.range_m - r_safe) < config_.circle_tolerance_m) {
    enter(DockingPhase::kFinal, c.now_s, "aligned with the port axis");
    return std::nullopt;
  }
  if (std::abs(g.range_m - r_safe) > kOffCircleTolerances * config_.circle_tolerance_m) {
    enter(DockingPhase::kApproach, c.now_s, fmt("off the safe circle by %.2f m", g.range_m - r_safe));
    return std::nullopt;
  }
  if (arc_m > min_goal_distance_m_ + config_.divergence_margin_m) {
    enter(DockingPhase::kAbort, c.now_s,
          fmt2("alignment diverging: %.2f m of arc left, was %.2f m", arc_m, min_goal_distance_m_));
    return std::nullopt;
  }
  min_goal_distance_m_ = std::min(min_goal_distance_m_, arc_m);
  return finish(c, drive(c, c.out, Phase::kAlign,
                         fmt("on the safe circle towards the port axis, %.0f deg to go", g.polar_angle_rad * kRadToDeg)));
}

std::optional<PlannerOutput> DockingPlanner::stepFinal(Cycle& c, const std::string& blind_reason) {
  const ApproachGeometry& g = c.out.geometry;
  if (g.tip_error_m <= config_.docked_position_tolerance_m &&
      std::abs(g.yaw_error_rad) <= config_.docked_yaw_tolerance_rad) {
    enter(DockingPhase::kDocked, c.now_s,
          fmt2("docked: probe tip %.1f mm from the port, yaw error %.2f deg", g.tip_error_m * 1000.0,
               g.yaw_error_rad * kRadToDeg) +
              (c.out.on_odometry ? " (final approach on odometry)" : ""));
    return std::nullopt;
  }
  if (std::abs(g.lateral_m) > config_.final_abort_lateral_m || std::abs(g.yaw_error_rad) > config_.final_abort_yaw_rad) {
    enter(DockingPhase::kAbort, c.now_s,
          fmt2("final approach errors growing: lateral %.3f m, yaw %.1f deg", g.lateral_m, g.yaw_error_rad * kRadToDeg));
    return std::nullopt;
  }
  return finish(c, drive(c, c.out, Phase::kFinal,
                         c.out.on_odometry ? "final approach " + blind_reason
                                           : std::string("final approach along the port axis")));
}

}  // namespace docking_planner
