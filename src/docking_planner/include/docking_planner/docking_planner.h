// The docking state machine around SafeCircleApproach (ROS-free). The node feeds it the target
// estimates (already in odom) and the chaser's odometry, and calls update() at a fixed rate.
//
//   IDLE     no docking asked for (the start-up state): zero velocity, whatever the cameras see;
//            estimates still go into the track, so a docking can start on a target already in view
//   SEARCH   no target: stop; after kSearchWaitS orbit where it was last seen (if within
//            search_orbit_memory_s), else turn slowly in place to look for it
//   APPROACH straight to the safe circle (see safe_circle_approach.h)
//   ALIGN    along the safe circle to the port axis
//   FINAL    along the port axis to contact; near contact, on odometry (the target pose held in odom)
//   DOCKED   within the docked tolerances: zero velocity for that cycle, then IDLE
//   HOLD     target lost (or odometry bad): zero velocity; back to where it was when the target
//            returns; after hold_timeout_s ABORT (inside the safe circle) or SEARCH. Perception gone
//            (no estimate message, the arbiter says no estimator talks, or a camera reports a fault
//            while the target is not seen): HOLD still, no SEARCH or ABORT (both need eyes), until it
//            returns (then the usual hold from that moment) or until the search timeout has passed:
//            then the docking ends, PERCEPTION_LOST, naming what is missing
//   ABORT    lost too long near the target, or errors growing: back off to the safe circle on the held
//            target pose, then SEARCH
// A docking runs from start() until it ends: DOCKED, cancel(), its time budget spent, no target for its
// search timeout, or perception gone for as long; every end goes back to IDLE and the cycle it ends in
// reports the outcome.
// Every failure path commands zero velocity: bad odometry, NaN, no target, HOLD, DOCKED, IDLE.
#pragma once

#include <cstdint>
#include <optional>
#include <string>
#include <vector>

#include <docking_msgs/estimate_check.h>

#include "docking_planner/safe_circle_approach.h"
#include "docking_planner/target_track.h"

namespace docking_planner {

/// Numbered as DockingState's constants.
enum class DockingPhase : std::uint8_t {
  kSearch = 0,
  kApproach = 1,
  kAlign = 2,
  kFinal = 3,
  kDocked = 4,
  kHold = 5,
  kAbort = 6,
  kIdle = 7
};
const char* stateName(DockingPhase state);

/// How a docking ended; numbered as docking_msgs/DockResult's constants.
enum class DockingOutcome : std::uint8_t {
  kDocked = 1,
  kCancelled = 2,
  kTimeBudget = 3,
  kTargetLost = 4,
  kClientGone = 5,
  kRejected = 6,
  kShutdown = 7,
  kPerceptionLost = 8
};
const char* outcomeName(DockingOutcome outcome);

// Constants of the state machine.
/// SEARCH stands still this long before it orbits or turns, s: the estimators settle after a start or a
/// lost target (30 frames of the 15 Hz cameras) before the chaser moves to look.
constexpr double kSearchWaitS = 2.0;
/// ABORT stops backing off after this long and searches, s: the longest back-off (from contact to the
/// 0.6 m circle at align_speed_mps, 0.15 m/s) takes ~4 s; 5x that for a moving target.
constexpr double kAbortTimeoutS = 20.0;
/// A goal that sets no search timeout (0) ends after this long without a target, or with perception
/// gone, s. The goal's search_timeout_s is the per-docking setting (`dock start --search-timeout`).
constexpr double kDefaultSearchTimeoutS = 60.0;

/// Limits of one docking (the action's goal). 0 means "the planner's configured value" / no limit.
struct DockingLimits {
  double time_budget_s{0.0};     ///< give up after this long; 0: no limit
  double search_timeout_s{0.0};  ///< give up after searching this long; 0: kDefaultSearchTimeoutS
  double max_speed_mps{0.0};     ///< cap on the linear speed; 0: the law's max_speed_mps
};
/// Empty when the limits are usable, otherwise why not (negative, NaN, infinite).
std::string checkLimits(const DockingLimits& limits);

/// The settings (settings/planner.yaml: PlannerConfig, with the law's and the track's) and what one
/// range cannot say (two settings that contradict); throws naming the bad field.
void validate(const PlannerConfig& config);


/// The chaser's odometry: pose of base_link in odom, body-frame twist.
struct ChaserOdometry {
  double stamp_s{0.0};
  Pose2D pose;
  BodyTwist twist;
};

struct PlannerOutput {
  DockingPhase state{DockingPhase::kSearch};
  std::string reason;
  double time_in_state_s{0.0};
  BodyTwist command;                   ///< base_link; all zero on every failure path
  bool target_visible{false};          ///< a valid, fresh estimate was used this cycle
  bool on_odometry{false};             ///< FINAL runs on the held target pose, not on fresh estimates
  std::uint8_t estimate_source{0};     ///< source of the last estimate used
  bool has_target{false};              ///< the errors below are meaningful (a target pose is held)
  ApproachGeometry geometry;           ///< errors against the (held or fresh) port pose
  double goal_distance_m{0.0};
  std::optional<PortState> port;       ///< the port pose the command was computed from
  /// port->pose.yaw is the port axis. False: position only (stereo far away, face turned away), and the
  /// yaw is the line of sight to the chaser that the law uses in its place.
  bool port_orientation_known{false};
  /// The current phase's goal (the base_link pose the law steers to), odom; absent when standing still.
  std::optional<Pose2D> goal;
  std::vector<Pose2D> path;            ///< planned path in odom (empty without a target)
  /// Set in the one cycle in which a docking ended by itself (DOCKED, time budget, target lost); the
  /// planner is IDLE from the next cycle on. Ends asked for with cancel() are not reported here.
  std::optional<DockingOutcome> outcome;
};

class DockingPlanner {
 public:
  /// probe_x_m: the docking probe tip on base_link +x (robot data, config/robot.yaml). Throws
  /// std::invalid_argument for an invalid configuration.
  DockingPlanner(const PlannerConfig& config, double probe_x_m);

  /// Gives the planner an estimate. Invalid, NaN and out-of-order ones are not used; the returned
  /// reason says why (and shows up in the next update's reason while the target is not visible).
  TrackUpdate addObservation(const TargetObservation& observation);

  /// A message arrived on the estimate topic at `now_s` (receipt time: its stamp may be anything).
  /// sources_silent: it says that no estimator has published (perception stalled or gone).
  void notePerception(double now_s, bool sources_silent);

  /// What the inputs' own diagnostics say is wrong now (e.g. a camera: its source unreadable), empty when
  /// nothing: cited while perception is gone and in the reason a docking ends with. With the target not
  /// seen, such a fault counts as perception gone (HOLD still: searching needs that camera).
  void setInputProblem(const std::string& problem) { input_problem_ = problem; }

  /// Why perception counts as gone at `now_s` (empty: it is there), with the inputs' faults.
  std::string perceptionProblem(double now_s) const;

  /// One planner cycle at time `now_s` with the latest odometry (absent: none received yet).
  PlannerOutput update(double now_s, const std::optional<ChaserOdometry>& odometry);

  /// Starts a docking (SEARCH) from IDLE. False, with the reason, for unusable limits or when a docking
  /// is already running (cancel() it first).
  bool start(double now_s, const DockingLimits& limits, std::string* why_not);

  /// Ends the running docking (if any): IDLE, zero velocity from the next update().
  void cancel(double now_s, const std::string& reason);

  /// IDLE, forgetting the target.
  void reset(double now_s);

  /// Forgets the target and its stamps but keeps the docking state (its clock restarts at `now_s`):
  /// after the clock jumped back (sim time reset, bag loop) the held stamps would refuse every
  /// new estimate as out of order.
  void forgetTarget(double now_s);

  /// A docking is running (any state but IDLE).
  bool active() const { return state_ != DockingPhase::kIdle; }
  /// Time since start() of the running docking, s (0 when IDLE).
  double elapsed(double now_s) const { return active() ? now_s - started_s_ : 0.0; }

  DockingPhase state() const { return state_; }
  const PlannerConfig& config() const { return config_; }
  double probeX() const { return law_.probeX(); }

 private:
  /// What one update() sees: the time, the chaser, the port predicted to now, and the output so far.
  struct Cycle {
    double now_s{0.0};
    std::string odom_problem;  ///< empty: the odometry is usable
    Pose2D chaser;
    PortState port;
    bool orientation_known{false};
    PlannerOutput out;
  };
  // The stages of update(), in order.
  std::string odometryProblem(double now_s, const std::optional<ChaserOdometry>& odometry) const;
  Cycle observe(double now_s, const std::optional<ChaserOdometry>& odometry);
  std::optional<PlannerOutput> checkInputs(Cycle& c);
  std::optional<PlannerOutput> holdWhilePerceptionGone(Cycle& c);
  PlannerOutput runStateMachine(Cycle& c);
  // One state's step: its output, or nothing after a transition (the new state runs in the same cycle).
  std::optional<PlannerOutput> stepState(Cycle& c);
  std::optional<PlannerOutput> stepSearch(Cycle& c);
  std::optional<PlannerOutput> stepHold(Cycle& c);
  std::optional<PlannerOutput> stepAbort(Cycle& c);
  std::optional<PlannerOutput> stepMoving(Cycle& c);
  bool continueOnOdometry(const Cycle& c, std::string* reason);
  std::optional<PlannerOutput> stepApproach(Cycle& c);
  std::optional<PlannerOutput> stepAlign(Cycle& c);
  std::optional<PlannerOutput> stepFinal(Cycle& c, const std::string& blind_reason);
  // The cycle's output: state and time in it, the speed cap; ending the docking; the law's command.
  PlannerOutput finish(const Cycle& c, PlannerOutput o) const;
  PlannerOutput endDocking(const Cycle& c, PlannerOutput o, DockingOutcome outcome, const std::string& reason);
  PlannerOutput drive(const Cycle& c, PlannerOutput o, Phase phase, const std::string& reason) const;
  static bool moving(DockingPhase state);

  void enter(DockingPhase state, double now_s, const std::string& reason);
  PlannerOutput stop(PlannerOutput out, const std::string& reason) const;
  bool targetVisible(double now_s) const;
  double searchTimeout() const;  // the goal's, else kDefaultSearchTimeoutS
  std::string lostReason(double now_s) const;
  /// Why an estimate inside the odometry-only range is not used (empty: it is; see contact_estimate_gate_m).
  std::string contactEstimateRejection(const TargetObservation& observation) const;
  /// Position only: to the search orbit around `port` (its orientation ignored: taken as facing the
  /// chaser), then round it counter-clockwise with the cameras on it. `why` prefixes the reason.
  PlannerOutput orbitForTheFace(PlannerOutput out, const Pose2D& chaser, PortState port,
                                const std::string& why) const;

  PlannerConfig config_;
  SafeCircleApproach law_;
  SafeCircleApproach orbit_law_;  // the same law on the search orbit (orientation unknown)
  TargetTrack track_;
  void scaleToSpeedCap(BodyTwist* command) const;

  DockingPhase state_{DockingPhase::kIdle};
  std::string state_reason_{"waiting for a docking goal"};
  DockingLimits limits_;     // of the running docking
  double started_s_{0.0};    // when it started
  std::optional<double> state_since_s_;
  DockingPhase resume_state_{DockingPhase::kApproach};  // where HOLD returns to
  double min_goal_distance_m_{0.0};                     // divergence check within APPROACH / ALIGN
  double last_tip_error_m_{1e9};                        // to ignore estimates at contact range
  std::string last_rejection_;
  bool nan_estimate_{false};  // the latest estimate offered had a NaN: treated as no target
  double last_seen_s_{-1e300};  // stamp of the last estimate taken, into the track or as "seen"
  double last_perception_s_{-1e300};  // receipt time of the last estimate message, valid or not
  bool sources_silent_{false};        // the last one said that no estimator talks
  bool perception_down_{false};       // the last update() found perception gone
  double perception_down_since_s_{0.0};  // since when (the search timeout counts from there)
  std::string input_problem_;          // setInputProblem()
};

}  // namespace docking_planner
