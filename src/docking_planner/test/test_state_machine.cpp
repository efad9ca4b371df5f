// State transitions of DockingPlanner, driven cycle by cycle with hand-placed chaser poses.
#include <gtest/gtest.h>

#include <cmath>
#include <stdexcept>

#include "docking_planner/docking_planner.h"
#include "shipped_config.h"

using namespace docking_planner;

namespace {

constexpr double kDt = 0.05;

bool isZero(const BodyTwist& t) { return t.vx == 0.0 && t.vy == 0.0 && t.wz == 0.0; }

ChaserOdometry odomAt(double t, const Pose2D& pose) {
  ChaserOdometry o;
  o.stamp_s = t;
  o.pose = pose;
  return o;
}

TargetObservation portAt(double t, const Pose2D& port) {
  TargetObservation o;
  o.stamp_s = t;
  o.valid = true;
  o.orientation_valid = true;
  o.pose = port;
  o.source = 1;
  return o;
}

// A port at the origin, axis along +x; the chaser placed by the test.
class StateMachineTest : public ::testing::Test {
 protected:
  const Pose2D port_{0.0, 0.0, 0.0};
  DockingPlanner planner_{shippedConfig(), shippedProbeX()};
  double t_{100.0};

  // Every test but the IDLE ones runs inside a docking.
  void SetUp() override { ASSERT_TRUE(planner_.start(t_, DockingLimits{}, nullptr)); }

  // One cycle: optionally an estimate, then update with odometry at `chaser`.
  PlannerOutput step(const Pose2D& chaser, bool see_target) {
    t_ += kDt;
    if (see_target) planner_.addObservation(portAt(t_, port_));
    planner_.notePerception(t_, false);  // perception alive (see PerceptionGone*)
    return planner_.update(t_, odomAt(t_, chaser));
  }
  // One cycle in which no estimate message arrives at all (perception gone), or in which the arbiter
  // says that no estimator talks (sources_silent).
  PlannerOutput stepPerceptionGone(const Pose2D& chaser, bool sources_silent) {
    t_ += kDt;
    if (sources_silent) planner_.notePerception(t_, true);
    return planner_.update(t_, odomAt(t_, chaser));
  }
  // Steps until the docking ends by itself (an output with an outcome), at most max_cycles.
  PlannerOutput stepUntilEnded(const Pose2D& chaser, bool see_target, int max_cycles) {
    PlannerOutput out;
    for (int i = 0; i < max_cycles && !out.outcome; ++i) out = step(chaser, see_target);
    return out;
  }
  PlannerOutput runFor(double seconds, const Pose2D& chaser, bool see_target) {
    PlannerOutput out;
    const int cycles = static_cast<int>(std::round(seconds / kDt));
    for (int i = 0; i < cycles; ++i) out = step(chaser, see_target);
    return out;
  }
};

const Pose2D kFar{3.0, 0.5, M_PI};            // 3 m out, facing the port
const Pose2D kOnCircleOff{0.6 * std::cos(0.8), 0.6 * std::sin(0.8), 0.8 + M_PI};  // on the circle, 46 deg off
const Pose2D kSafePoint{0.6, 0.0, M_PI};      // on the axis, aligned
const Pose2D kNearContact{0.18 + 0.05, 0.0, M_PI};  // probe tip 5 cm from the port
const Pose2D kDocked{0.18 + 0.002, 0.0, M_PI};      // probe tip 2 mm from the port

}  // namespace

TEST(DockingPlannerConfig, RejectsInvalidValuesWithTheirName) {
  PlannerConfig c = shippedConfig();
  c.hold_timeout_s = -1.0;
  try {
    DockingPlanner p{c, shippedProbeX()};
    FAIL() << "accepted a negative hold timeout";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("hold_timeout_s"), std::string::npos);
  }
  c = shippedConfig();
  c.law.safe_radius_m = NAN;
  EXPECT_THROW(DockingPlanner(c, shippedProbeX()), std::invalid_argument);
  c = shippedConfig();
  c.input_timeout_s = 1e9;  // the chaser would drive on a dead perception
  EXPECT_THROW(DockingPlanner(c, shippedProbeX()), std::invalid_argument);
}

TEST_F(StateMachineTest, SearchStopsThenTurnsSlowly) {
  PlannerOutput out = step(kFar, false);
  EXPECT_EQ(out.state, DockingPhase::kSearch);
  EXPECT_TRUE(isZero(out.command));
  EXPECT_NE(out.reason.find("no target"), std::string::npos) << out.reason;
  out = runFor(kSearchWaitS + 0.2, kFar, false);
  EXPECT_EQ(out.state, DockingPhase::kSearch);
  EXPECT_EQ(out.command.vx, 0.0);
  EXPECT_EQ(out.command.vy, 0.0);
  EXPECT_DOUBLE_EQ(out.command.wz, planner_.config().search_yaw_rate_radps);
}

TEST_F(StateMachineTest, FullSequenceSearchApproachAlignFinalDocked) {
  EXPECT_EQ(step(kFar, false).state, DockingPhase::kSearch);
  PlannerOutput out = step(kFar, true);
  EXPECT_EQ(out.state, DockingPhase::kApproach);
  EXPECT_FALSE(isZero(out.command));
  EXPECT_TRUE(out.target_visible);
  // At the approach goal on the circle (for this pose the goal is the tangent-limited point: put the
  // chaser where the law aims).
  const Pose2D chaser_on_circle = kOnCircleOff;
  out = step(chaser_on_circle, true);
  EXPECT_EQ(out.state, DockingPhase::kAlign) << out.reason;
  // Moves along the circle towards the axis (decreasing polar angle: clockwise here).
  const Vec2 increasing = perpendicular(chaser_on_circle.position().normalized());
  const Vec2 v_odom(std::cos(chaser_on_circle.yaw) * out.command.vx - std::sin(chaser_on_circle.yaw) * out.command.vy,
                    std::sin(chaser_on_circle.yaw) * out.command.vx + std::cos(chaser_on_circle.yaw) * out.command.vy);
  EXPECT_LT(v_odom.dot(increasing), 0.0);
  out = step(kSafePoint, true);
  EXPECT_EQ(out.state, DockingPhase::kFinal) << out.reason;
  EXPECT_GT(out.command.vx, 0.0);
  out = step(kDocked, true);
  EXPECT_EQ(out.state, DockingPhase::kDocked) << out.reason;
  EXPECT_TRUE(isZero(out.command));
  ASSERT_TRUE(out.outcome.has_value());
  EXPECT_EQ(*out.outcome, DockingOutcome::kDocked);
  // The docking is over: IDLE with zero velocity, whatever happens next, until the next start().
  EXPECT_FALSE(planner_.active());
  out = step(kFar, true);
  EXPECT_EQ(out.state, DockingPhase::kIdle);
  EXPECT_FALSE(out.outcome.has_value());
  EXPECT_EQ(runFor(10.0, kFar, true).state, DockingPhase::kIdle);
  EXPECT_TRUE(isZero(step(kFar, true).command));
}

TEST_F(StateMachineTest, LostBrieflyHoldsWithZeroVelocityThenResumes) {
  step(kFar, true);
  ASSERT_EQ(step(kFar, true).state, DockingPhase::kApproach);
  // Estimates stop: within the estimate timeout the planner keeps going on the last one...
  EXPECT_EQ(step(kFar, false).state, DockingPhase::kApproach);
  // ...then holds, with zero velocity.
  PlannerOutput out = runFor(planner_.config().estimate_timeout_s + 0.1, kFar, false);
  EXPECT_EQ(out.state, DockingPhase::kHold);
  EXPECT_TRUE(isZero(out.command));
  EXPECT_NE(out.reason.find("not seen"), std::string::npos) << out.reason;
  out = runFor(1.0, kFar, false);
  EXPECT_EQ(out.state, DockingPhase::kHold);
  EXPECT_TRUE(isZero(out.command));
  // The target comes back: resume the approach.
  out = step(kFar, true);
  EXPECT_EQ(out.state, DockingPhase::kApproach);
  EXPECT_FALSE(isZero(out.command));
}

TEST_F(StateMachineTest, LostTooLongOutsideTheCircleSearches) {
  step(kFar, true);
  ASSERT_EQ(step(kFar, true).state, DockingPhase::kApproach);
  const PlannerConfig& c = planner_.config();
  // Every cycle until SEARCH is HOLD with zero velocity.
  PlannerOutput out;
  bool saw_hold = false;
  for (int i = 0; i < static_cast<int>((c.estimate_timeout_s + c.hold_timeout_s + 0.5) / kDt); ++i) {
    out = step(kFar, false);
    if (out.state == DockingPhase::kHold) {
      saw_hold = true;
      EXPECT_TRUE(isZero(out.command));
    }
  }
  EXPECT_TRUE(saw_hold);
  EXPECT_EQ(out.state, DockingPhase::kSearch);
  EXPECT_TRUE(isZero(out.command));  // SEARCH starts by standing still
}

// A target lost at 3 m (its face turned away, the detector blind to its side): after the standing
// wait, SEARCH goes to the search orbit around where it was and round it, the cameras on it; once it
// has not been seen for search_orbit_memory_s, it turns in place as for a target never seen.
TEST_F(StateMachineTest, SearchLooksWhereTheTargetWasLastSeen) {
  const PlannerConfig& c = planner_.config();
  ASSERT_GT(c.search_orbit_memory_s, c.estimate_timeout_s + c.hold_timeout_s + kSearchWaitS + 1.0);
  step(kFar, true);
  ASSERT_EQ(step(kFar, true).state, DockingPhase::kApproach);
  const double lost_at = t_;
  PlannerOutput out = runFor(c.estimate_timeout_s + c.hold_timeout_s + 0.2, kFar, false);
  ASSERT_EQ(out.state, DockingPhase::kSearch) << out.reason;
  out = runFor(kSearchWaitS + 0.2, kFar, false);
  ASSERT_EQ(out.state, DockingPhase::kSearch) << out.reason;
  EXPECT_NE(out.reason.find("looking where it was"), std::string::npos) << out.reason;
  // Towards the held port (the chaser faces it: +x in base_link), to the orbit, not to the safe circle.
  EXPECT_GT(out.command.vx, 0.1);
  EXPECT_NEAR(out.goal_distance_m, std::hypot(kFar.x, kFar.y) - c.search_orbit_radius_m, 0.05);

  // On the orbit: along it, counter-clockwise (+y at this point), turning towards the port.
  const Pose2D on_orbit{c.search_orbit_radius_m, 0.0, M_PI + 0.3};
  out = step(on_orbit, false);
  EXPECT_EQ(out.state, DockingPhase::kSearch);
  const double vy_odom = std::sin(on_orbit.yaw) * out.command.vx + std::cos(on_orbit.yaw) * out.command.vy;
  EXPECT_GT(vy_odom, 0.9 * c.orbit_speed_mps);
  EXPECT_LT(out.command.wz, 0.0);

  // Not seen for longer than the memory: turns in place.
  out = runFor(lost_at + c.search_orbit_memory_s + 0.5 - t_, kFar, false);
  ASSERT_EQ(out.state, DockingPhase::kSearch) << out.reason;
  EXPECT_EQ(out.command.vx, 0.0);
  EXPECT_EQ(out.command.vy, 0.0);
  EXPECT_DOUBLE_EQ(out.command.wz, c.search_yaw_rate_radps);
}

TEST(DockingPlannerConfig, SearchOrbitMemoryZeroAlwaysTurnsInPlace) {
  PlannerConfig c = shippedConfig();
  c.search_orbit_memory_s = -1.0;
  EXPECT_THROW(DockingPlanner(c, shippedProbeX()), std::invalid_argument);
  c.search_orbit_memory_s = 0.0;
  DockingPlanner planner{c, shippedProbeX()};
  double t = 10.0;
  ASSERT_TRUE(planner.start(t, DockingLimits{}, nullptr));
  planner.addObservation(portAt(t, Pose2D{0.0, 0.0, 0.0}));
  PlannerOutput out;
  for (; t < 10.0 + c.estimate_timeout_s + c.hold_timeout_s + kSearchWaitS + 1.0; t += kDt) {
    planner.notePerception(t, false);
    out = planner.update(t, odomAt(t, kFar));
  }
  ASSERT_EQ(out.state, DockingPhase::kSearch) << out.reason;
  EXPECT_EQ(out.command.vx, 0.0);
  EXPECT_DOUBLE_EQ(out.command.wz, c.search_yaw_rate_radps);
}

TEST_F(StateMachineTest, LostTooLongInsideTheCircleAbortsBacksOffThenSearches) {
  // Get into FINAL, just inside the circle: 0.54 m from the port (inside 0.6 - 0.05), probe tip
  // 0.36 m from it (beyond the 0.35 m blind range, so a lost target is a HOLD, not odometry).
  step(kOnCircleOff, true);
  step(kSafePoint, true);
  const Pose2D halfway{0.54, 0.0, M_PI};
  ASSERT_EQ(step(halfway, true).state, DockingPhase::kFinal);
  const PlannerConfig& c = planner_.config();
  PlannerOutput out = runFor(c.estimate_timeout_s + 0.1, halfway, false);
  EXPECT_EQ(out.state, DockingPhase::kHold);
  EXPECT_TRUE(isZero(out.command));
  out = runFor(c.hold_timeout_s + 0.1, halfway, false);
  EXPECT_EQ(out.state, DockingPhase::kAbort) << out.reason;
  // Backing off: radially out (+x here), on the held pose.
  EXPECT_LT(out.command.vx, 0.0);  // facing the port, so backwards in the body frame
  EXPECT_NEAR(out.command.vy, 0.0, 1e-9);
  // Once on the circle: SEARCH, standing still.
  out = step(Pose2D{0.6, 0.0, M_PI}, false);
  EXPECT_EQ(out.state, DockingPhase::kSearch) << out.reason;
  EXPECT_TRUE(isZero(out.command));
}

TEST_F(StateMachineTest, PerceptionGoneHoldsStillPastTheHoldTimeoutThenResumes) {
  step(kFar, true);
  ASSERT_EQ(step(kFar, true).state, DockingPhase::kApproach);
  const PlannerConfig& c = planner_.config();
  // No estimate message at all: within input_timeout_s the planner stops and holds...
  PlannerOutput out;
  double stopped_after_s = -1.0;
  for (double waited = kDt; waited < c.input_timeout_s + 0.2; waited += kDt) {
    out = stepPerceptionGone(kFar, false);
    if (stopped_after_s < 0.0 && isZero(out.command)) stopped_after_s = waited;
  }
  EXPECT_EQ(out.state, DockingPhase::kHold);
  EXPECT_GT(stopped_after_s, 0.0);
  EXPECT_LE(stopped_after_s, c.input_timeout_s + 2 * kDt);
  // ...for as long as perception is gone, long past the hold's timeout: no SEARCH turning, no ABORT.
  for (double waited = 0.0; waited < 3.0 * c.hold_timeout_s; waited += kDt) {
    out = stepPerceptionGone(kFar, false);
    ASSERT_EQ(out.state, DockingPhase::kHold) << out.reason;
    ASSERT_TRUE(isZero(out.command));
  }
  // Perception back with the target: the approach resumes.
  out = step(kFar, true);
  EXPECT_EQ(out.state, DockingPhase::kApproach) << out.reason;
  EXPECT_FALSE(isZero(out.command));
}

// Issue 54: a camera with no frames left the planner in HOLD for ever. Perception gone for the search
// timeout (the goal's here) ends the docking, PERCEPTION_LOST, zero velocity, naming the camera at fault.
TEST_F(StateMachineTest, PerceptionGoneForTheSearchTimeoutEndsTheDockingNamingTheCamera) {
  planner_.cancel(t_, "restart with a goal's search timeout");
  DockingLimits limits;
  limits.search_timeout_s = 5.0;
  ASSERT_TRUE(planner_.start(t_, limits, nullptr));
  step(kFar, true);
  ASSERT_EQ(step(kFar, true).state, DockingPhase::kApproach);
  planner_.setInputProblem("camera stereo_camera: left: no readable image matches image sequence /x_%04d.png");
  PlannerOutput out;
  double ended_after_s = -1.0;
  for (double waited = kDt; waited < 8.0 && ended_after_s < 0.0; waited += kDt) {
    out = stepPerceptionGone(kFar, true);
    ASSERT_TRUE(isZero(out.command));
    if (out.outcome) {
      ended_after_s = waited;
    } else {
      ASSERT_EQ(out.state, DockingPhase::kHold) << out.reason;
    }
  }
  ASSERT_TRUE(out.outcome.has_value());
  EXPECT_EQ(*out.outcome, DockingOutcome::kPerceptionLost);
  EXPECT_GE(ended_after_s, limits.search_timeout_s);
  EXPECT_LE(ended_after_s, limits.search_timeout_s + 2 * kDt);
  EXPECT_NE(out.reason.find("no estimator publishes"), std::string::npos) << out.reason;
  EXPECT_NE(out.reason.find("camera stereo_camera"), std::string::npos) << out.reason;
  EXPECT_FALSE(planner_.active());
  EXPECT_TRUE(isZero(stepPerceptionGone(kFar, true).command));
}

// A camera at fault while another still sees the target: the docking goes on. With the target not seen
// it does not search (that needs the camera) but holds still, then ends as above.
TEST_F(StateMachineTest, CameraFaultHoldsOnlyWhileTheTargetIsNotSeen) {
  step(kFar, true);
  ASSERT_EQ(step(kFar, true).state, DockingPhase::kApproach);
  planner_.setInputProblem("camera ir_camera: /dev/ir does not exist (not plugged in?)");
  PlannerOutput out = step(kFar, true);
  EXPECT_EQ(out.state, DockingPhase::kApproach) << out.reason;
  EXPECT_FALSE(isZero(out.command));
  const PlannerConfig& c = planner_.config();
  out = runFor(c.hold_timeout_s + kSearchWaitS + 1.0, kFar, false);  // long enough to search, normally
  EXPECT_EQ(out.state, DockingPhase::kHold) << out.reason;
  EXPECT_TRUE(isZero(out.command));
  EXPECT_NE(out.reason.find("ir_camera"), std::string::npos) << out.reason;
  out = stepUntilEnded(kFar, false, static_cast<int>((kDefaultSearchTimeoutS + 1.0) / kDt));
  ASSERT_TRUE(out.outcome.has_value()) << out.reason;
  EXPECT_EQ(*out.outcome, DockingOutcome::kPerceptionLost);
  EXPECT_NE(out.reason.find("ir_camera"), std::string::npos) << out.reason;
}

TEST_F(StateMachineTest, ArbiterSayingNoEstimatorTalksStopsAtOnce) {
  step(kFar, true);
  ASSERT_EQ(step(kFar, true).state, DockingPhase::kApproach);
  const PlannerOutput out = stepPerceptionGone(kFar, true);
  EXPECT_EQ(out.state, DockingPhase::kHold);
  EXPECT_TRUE(isZero(out.command));
  EXPECT_NE(planner_.perceptionProblem(t_), "");
}

TEST_F(StateMachineTest, PerceptionBackWithoutTheTargetHoldsTheUsualTimeFromThen) {
  step(kFar, true);
  ASSERT_EQ(step(kFar, true).state, DockingPhase::kApproach);
  const PlannerConfig& c = planner_.config();
  for (double waited = 0.0; waited < 2.0 * c.hold_timeout_s; waited += kDt) stepPerceptionGone(kFar, false);
  // Estimates arrive again but none is valid: still HOLD (the timeout restarted), then SEARCH.
  PlannerOutput out = runFor(c.hold_timeout_s - 0.5, kFar, false);
  EXPECT_EQ(out.state, DockingPhase::kHold) << out.reason;
  out = runFor(1.0, kFar, false);
  EXPECT_EQ(out.state, DockingPhase::kSearch) << out.reason;
}

TEST_F(StateMachineTest, NanEstimateStopsAndSaysWhy) {
  step(kFar, true);
  ASSERT_EQ(step(kFar, true).state, DockingPhase::kApproach);
  t_ += kDt;
  TargetObservation bad = portAt(t_, port_);
  bad.pose.y = NAN;
  EXPECT_FALSE(planner_.addObservation(bad).accepted);
  planner_.notePerception(t_, false);  // perception alive (see PerceptionGone*)
  const PlannerOutput out = planner_.update(t_, odomAt(t_, kFar));
  EXPECT_EQ(out.state, DockingPhase::kHold);
  EXPECT_TRUE(isZero(out.command));
  EXPECT_NE(out.reason.find("NaN"), std::string::npos) << out.reason;
  // A good estimate clears it.
  EXPECT_EQ(step(kFar, true).state, DockingPhase::kApproach);
}

TEST_F(StateMachineTest, BadOdometryStopsAndSaysWhy) {
  step(kFar, true);
  ASSERT_EQ(step(kFar, true).state, DockingPhase::kApproach);
  t_ += kDt;
  planner_.addObservation(portAt(t_, port_));
  ChaserOdometry nan_odom = odomAt(t_, kFar);
  nan_odom.twist.wz = NAN;
  planner_.notePerception(t_, false);  // perception alive (see PerceptionGone*)
  PlannerOutput out = planner_.update(t_, nan_odom);
  EXPECT_TRUE(isZero(out.command));
  EXPECT_EQ(out.state, DockingPhase::kHold);
  EXPECT_NE(out.reason.find("odometry"), std::string::npos) << out.reason;

  t_ += kDt;
  planner_.addObservation(portAt(t_, port_));
  planner_.notePerception(t_, false);  // perception alive (see PerceptionGone*)
  out = planner_.update(t_, odomAt(t_ - 1.0, kFar));  // a second old
  EXPECT_TRUE(isZero(out.command));
  EXPECT_NE(out.reason.find("stale"), std::string::npos) << out.reason;

  planner_.notePerception(t_, false);  // perception alive (see PerceptionGone*)
  out = planner_.update(t_, std::nullopt);
  EXPECT_TRUE(isZero(out.command));
  EXPECT_NE(out.reason.find("no odometry"), std::string::npos) << out.reason;

  // Good odometry again: the approach resumes.
  EXPECT_EQ(step(kFar, true).state, DockingPhase::kApproach);

  // NaN planner time is refused too.
  EXPECT_TRUE(isZero(planner_.update(NAN, odomAt(t_, kFar)).command));
}

TEST_F(StateMachineTest, FinalNearContactFinishesOnOdometryWhenTheTargetIsLost) {
  step(kOnCircleOff, true);
  step(kSafePoint, true);
  ASSERT_EQ(step(kNearContact, true).state, DockingPhase::kFinal);
  // The cameras lose the target at 5 cm: FINAL goes on, on the held pose, and says so.
  const PlannerOutput out = runFor(2.0, kNearContact, false);
  EXPECT_EQ(out.state, DockingPhase::kFinal) << out.reason;
  EXPECT_TRUE(out.on_odometry);
  EXPECT_FALSE(out.target_visible);
  EXPECT_GT(out.command.vx, 0.0);
  EXPECT_NE(out.reason.find("odometry"), std::string::npos) << out.reason;
  // Reaching the port on odometry docks.
  const PlannerOutput docked = step(kDocked, false);
  EXPECT_EQ(docked.state, DockingPhase::kDocked) << docked.reason;
  EXPECT_NE(docked.reason.find("odometry"), std::string::npos) << docked.reason;
}

TEST_F(StateMachineTest, FinalBlindForTooLongAborts) {
  step(kOnCircleOff, true);
  step(kSafePoint, true);
  ASSERT_EQ(step(kNearContact, true).state, DockingPhase::kFinal);
  const PlannerOutput out = runFor(planner_.config().max_blind_s + 0.5, kNearContact, false);
  EXPECT_EQ(out.state, DockingPhase::kAbort) << out.reason;
}

TEST_F(StateMachineTest, FinalErrorsGrowingAbort) {
  step(kOnCircleOff, true);
  ASSERT_EQ(step(kSafePoint, true).state, DockingPhase::kFinal);
  // Pushed 10 cm off the axis.
  const PlannerOutput out = step(Pose2D{0.45, 0.10, M_PI}, true);
  EXPECT_EQ(out.state, DockingPhase::kAbort) << out.reason;
  EXPECT_NE(out.reason.find("errors growing"), std::string::npos) << out.reason;
  EXPECT_GT(out.command.vx * -1.0, 0.0);  // backing off: the chaser faces the port, so vx < 0
}

TEST_F(StateMachineTest, ApproachDivergingAborts) {
  step(kFar, true);
  ASSERT_EQ(step(kFar, true).state, DockingPhase::kApproach);
  // Something drags the chaser 0.5 m further away.
  const PlannerOutput out = step(Pose2D{kFar.x + 0.5, kFar.y, kFar.yaw}, true);
  EXPECT_EQ(out.state, DockingPhase::kAbort) << out.reason;
  EXPECT_NE(out.reason.find("diverging"), std::string::npos) << out.reason;
  EXPECT_TRUE(isZero(out.command));  // outside the circle there is nothing to back off from
  // Next cycle: through SEARCH, which still sees the target, to a fresh APPROACH.
  const PlannerOutput next = step(Pose2D{kFar.x + 0.5, kFar.y, kFar.yaw}, true);
  EXPECT_EQ(next.state, DockingPhase::kApproach) << next.reason;
  EXPECT_DOUBLE_EQ(next.time_in_state_s, 0.0);
}

TEST_F(StateMachineTest, ErrorsReportedForDockingState) {
  step(kFar, true);
  const PlannerOutput out = step(kFar, true);
  ASSERT_TRUE(out.has_target);
  EXPECT_NEAR(out.geometry.range_m, std::hypot(3.0, 0.5), 1e-9);
  EXPECT_NEAR(out.geometry.lateral_m, 0.5, 1e-9);
  EXPECT_NEAR(out.geometry.axial_m, 3.0, 1e-9);
  EXPECT_GT(out.goal_distance_m, 2.0);
  EXPECT_GE(out.path.size(), 3u);
  EXPECT_EQ(out.estimate_source, 1);
}

TEST_F(StateMachineTest, ResetEndsTheDockingAndForgetsTheTarget) {
  step(kOnCircleOff, true);
  ASSERT_EQ(step(kOnCircleOff, true).state, DockingPhase::kAlign);
  planner_.reset(t_);
  const PlannerOutput out = step(kOnCircleOff, false);
  EXPECT_EQ(out.state, DockingPhase::kIdle);
  EXPECT_FALSE(out.has_target);
  EXPECT_TRUE(isZero(out.command));
}

// ---- Docking on command: IDLE until start(), every end back to IDLE with zero velocity ----

TEST(DockingOnCommand, StartsIdleAndNeverMovesWithoutAGoal) {
  DockingPlanner planner{shippedConfig(), shippedProbeX()};
  const Pose2D port{0.0, 0.0, 0.0};
  double t = 10.0;
  for (int i = 0; i < 400; ++i, t += kDt) {  // 20 s with the target in plain view
    planner.addObservation(portAt(t, port));
    planner.notePerception(t, false);
    const PlannerOutput out = planner.update(t, odomAt(t, kFar));
    ASSERT_EQ(out.state, DockingPhase::kIdle);
    ASSERT_TRUE(isZero(out.command)) << "moved at " << t;
    ASSERT_FALSE(out.outcome.has_value());
  }
  // The target was tracked meanwhile: the errors are there for a user to see.
  planner.notePerception(t, false);
  EXPECT_TRUE(planner.update(t, odomAt(t, kFar)).has_target);
  EXPECT_FALSE(planner.active());
}

TEST(DockingOnCommand, RejectsUnusableLimitsAndASecondStart) {
  DockingPlanner planner{shippedConfig(), shippedProbeX()};
  std::string why;
  DockingLimits bad;
  bad.time_budget_s = -1.0;
  EXPECT_FALSE(planner.start(1.0, bad, &why));
  EXPECT_NE(why.find("time_budget_s"), std::string::npos) << why;
  bad = DockingLimits{};
  bad.max_speed_mps = NAN;
  EXPECT_FALSE(planner.start(1.0, bad, &why));
  EXPECT_NE(why.find("max_speed_mps"), std::string::npos) << why;
  EXPECT_FALSE(planner.active());
  ASSERT_TRUE(planner.start(1.0, DockingLimits{}, &why));
  EXPECT_FALSE(planner.start(1.1, DockingLimits{}, &why));
  EXPECT_NE(why.find("already running"), std::string::npos) << why;
}

TEST_F(StateMachineTest, CancelStopsAtOnceAndGoesIdle) {
  step(kFar, true);
  ASSERT_FALSE(isZero(step(kFar, true).command));
  planner_.cancel(t_, "cancelled by the client");
  const PlannerOutput out = step(kFar, true);
  EXPECT_EQ(out.state, DockingPhase::kIdle);
  EXPECT_TRUE(isZero(out.command));
  EXPECT_EQ(out.reason, "cancelled by the client");
  EXPECT_FALSE(out.outcome.has_value());  // asked for: the caller knows
  // A new goal starts where the target is.
  ASSERT_TRUE(planner_.start(t_, DockingLimits{}, nullptr));
  EXPECT_EQ(step(kFar, true).state, DockingPhase::kApproach);
}

TEST_F(StateMachineTest, TimeBudgetEndsTheDocking) {
  planner_.cancel(t_, "test");
  DockingLimits limits;
  limits.time_budget_s = 2.0;
  ASSERT_TRUE(planner_.start(t_, limits, nullptr));
  PlannerOutput out = runFor(1.9, kFar, true);
  EXPECT_EQ(out.state, DockingPhase::kApproach);
  EXPECT_FALSE(out.outcome.has_value());
  out = stepUntilEnded(kFar, true, 4);
  ASSERT_TRUE(out.outcome.has_value());
  EXPECT_EQ(*out.outcome, DockingOutcome::kTimeBudget);
  EXPECT_TRUE(isZero(out.command));
  EXPECT_EQ(step(kFar, true).state, DockingPhase::kIdle);
}

TEST_F(StateMachineTest, SearchingPastTheTimeoutEndsAsTargetLost) {
  planner_.cancel(t_, "test");
  DockingLimits limits;
  limits.search_timeout_s = 5.0;
  ASSERT_TRUE(planner_.start(t_, limits, nullptr));
  PlannerOutput out = runFor(4.9, kFar, false);
  EXPECT_EQ(out.state, DockingPhase::kSearch);
  EXPECT_FALSE(isZero(out.command));  // turning to look
  out = stepUntilEnded(kFar, false, 10);
  ASSERT_TRUE(out.outcome.has_value());
  EXPECT_EQ(*out.outcome, DockingOutcome::kTargetLost);
  EXPECT_TRUE(isZero(out.command));
  EXPECT_EQ(step(kFar, false).state, DockingPhase::kIdle);
}

TEST_F(StateMachineTest, SpeedCapOfTheGoalLimitsTheLinearSpeed) {
  step(kFar, true);
  const PlannerOutput free_run = step(kFar, true);
  ASSERT_GT(std::hypot(free_run.command.vx, free_run.command.vy), 0.1);
  planner_.cancel(t_, "test");
  DockingLimits limits;
  limits.max_speed_mps = 0.05;
  ASSERT_TRUE(planner_.start(t_, limits, nullptr));
  step(kFar, true);
  const PlannerOutput capped = step(kFar, true);
  EXPECT_EQ(capped.state, DockingPhase::kApproach);
  EXPECT_NEAR(std::hypot(capped.command.vx, capped.command.vy), 0.05, 1e-9);
}

TEST_F(StateMachineTest, PositionOnlyApproachesToTheSearchOrbitThenOrbitsFacingTheTarget) {
  const PlannerConfig& c = planner_.config();
  ASSERT_GT(c.search_orbit_radius_m, c.law.safe_radius_m);
  auto positionOnly = [&](double stamp) {
    TargetObservation o = portAt(stamp, port_);
    o.orientation_valid = false;
    o.source = 0;
    return o;
  };
  // Far: towards the target, and the goal is on the search orbit, not on the safe circle.
  t_ += kDt;
  planner_.addObservation(positionOnly(t_));
  planner_.notePerception(t_, false);  // perception alive (see PerceptionGone*)
  PlannerOutput out = planner_.update(t_, odomAt(t_, kFar));
  t_ += kDt;
  planner_.addObservation(positionOnly(t_));
  planner_.notePerception(t_, false);  // perception alive (see PerceptionGone*)
  out = planner_.update(t_, odomAt(t_, kFar));
  EXPECT_EQ(out.state, DockingPhase::kApproach);
  EXPECT_NE(out.reason.find("position only"), std::string::npos) << out.reason;
  EXPECT_GT(out.command.vx, 0.1);  // the chaser faces the target (yaw pi): advancing is +x in base_link
  const double far_range = std::hypot(kFar.x, kFar.y);
  EXPECT_NEAR(out.goal_distance_m, far_range - c.search_orbit_radius_m, 0.05);
  // Reported for display: the port's axis is not known, the goal lies on the search orbit.
  EXPECT_FALSE(out.port_orientation_known);
  ASSERT_TRUE(out.goal);
  EXPECT_NEAR(std::hypot(out.goal->x - port_.x, out.goal->y - port_.y), c.search_orbit_radius_m, 1e-9);

  // On the orbit, looking 0.3 rad to the side of the target: moves along the orbit (no radial
  // motion into it), and turns towards the target.
  const double r = c.search_orbit_radius_m;
  const Pose2D on_orbit{r, 0.0, M_PI + 0.3};
  t_ += kDt;
  planner_.addObservation(positionOnly(t_));
  planner_.notePerception(t_, false);  // perception alive (see PerceptionGone*)
  out = planner_.update(t_, odomAt(t_, on_orbit));
  EXPECT_EQ(out.state, DockingPhase::kApproach);
  EXPECT_NE(out.reason.find("orbiting"), std::string::npos) << out.reason;
  const double speed = std::hypot(out.command.vx, out.command.vy);
  EXPECT_NEAR(speed, c.orbit_speed_mps, 1e-6);
  // Odom velocity: rotate body -> odom; tangential (+y at this point: counter-clockwise), not radial.
  const double vx_odom = std::cos(on_orbit.yaw) * out.command.vx - std::sin(on_orbit.yaw) * out.command.vy;
  const double vy_odom = std::sin(on_orbit.yaw) * out.command.vx + std::cos(on_orbit.yaw) * out.command.vy;
  EXPECT_GT(vy_odom, 0.9 * c.orbit_speed_mps);
  EXPECT_NEAR(vx_odom, 0.0, 0.02);
  EXPECT_LT(out.command.wz, 0.0);  // the target is at -0.3 rad from the heading: turn right
  // The safe circle was never the goal: the chaser is well outside it.
  EXPECT_GT(out.geometry.range_m, c.law.safe_radius_m + 0.5);
}

TEST_F(StateMachineTest, PositionOnlyEstimateFarFromTheHeldTargetIsNotUsed) {
  const PlannerConfig& c = planner_.config();
  ASSERT_GT(c.position_only_gate_m, 0.0);
  runFor(0.5, kFar, true);  // target held at the origin
  TargetObservation elsewhere = portAt(t_ + kDt, Pose2D{2.0, 2.0, 0.0});  // another object of the room
  elsewhere.orientation_valid = false;
  const TrackUpdate rejected = planner_.addObservation(elsewhere);
  EXPECT_FALSE(rejected.accepted);
  EXPECT_NE(rejected.reason.find("from the held target"), std::string::npos) << rejected.reason;
  // Near the held target: used.
  TargetObservation near = portAt(t_ + 2 * kDt, Pose2D{0.005, -0.005, 0.0});
  near.orientation_valid = false;
  EXPECT_TRUE(planner_.addObservation(near).accepted);  // Persistent far estimates never restart the track while it is fresh: after many of them, the
  // target is still held at the origin and, unseen, the planner holds.
  for (int i = 0; i < 20; ++i) {
    t_ += kDt;
    TargetObservation o = portAt(t_ + 2 * kDt, Pose2D{2.0, 2.0, 0.0});
    o.orientation_valid = false;
    EXPECT_FALSE(planner_.addObservation(o).accepted);
    planner_.notePerception(t_, false);  // perception alive (see PerceptionGone*)
    planner_.update(t_, odomAt(t_, kFar));
  }
  planner_.notePerception(t_, false);  // perception alive (see PerceptionGone*)
  const PlannerOutput out = planner_.update(t_, odomAt(t_, kFar));
  EXPECT_EQ(out.state, DockingPhase::kHold);
  EXPECT_TRUE(isZero(out.command));
  ASSERT_TRUE(out.port.has_value());
  EXPECT_LT(std::hypot(out.port->pose.x, out.port->pose.y), 0.1);
}

TEST_F(StateMachineTest, PositionOnlyEstimatesDoNotMoveAPortHeldFromPoses) {
  runFor(1.0, kFar, true);  // poses (with orientation, default noise) of a port at the origin
  // Three seconds of stereo blob centres 10 cm to the side, each claiming 1 cm accuracy: they keep
  // the target seen (no HOLD), but the held port stays where the poses put it.
  for (int i = 0; i < 60; ++i) {
    t_ += kDt;
    TargetObservation blob = portAt(t_, Pose2D{0.0, 0.10, 0.0});
    blob.orientation_valid = false;
    blob.position_sigma_m = 0.01;
    EXPECT_TRUE(planner_.addObservation(blob).accepted);
    planner_.notePerception(t_, false);  // perception alive (see PerceptionGone*)
    const PlannerOutput out = planner_.update(t_, odomAt(t_, kFar));
    EXPECT_NE(out.state, DockingPhase::kHold);
  }
  planner_.notePerception(t_, false);  // perception alive (see PerceptionGone*)
  const PlannerOutput out = planner_.update(t_, odomAt(t_, kFar));
  ASSERT_TRUE(out.port.has_value());
  EXPECT_LT(std::abs(out.port->pose.y), 0.002) << "the blob pulled the held port to y = " << out.port->pose.y;
}

// Inside the odometry-only range, full poses near the held port keep updating it (contact_estimate_gate_m:
// the inner pattern to contact); a jump, a position-only estimate, or the gate off: not used.
TEST(ContactEstimates, FullPosesNearTheHeldPortAreUsedToContact) {
  for (const bool gate_on : {false, true}) {
    PlannerConfig c = shippedConfig();
    c.contact_estimate_gate_m = gate_on ? 0.03 : 0.0;
    c.contact_estimate_gate_yaw_rad = gate_on ? 0.05 : 0.0;
    DockingPlanner planner{c, shippedProbeX()};
    double t = 100.0;
    ASSERT_TRUE(planner.start(t, DockingLimits{}, nullptr));
    const Pose2D port{0.0, 0.0, 0.0};
    for (const Pose2D& chaser : {kOnCircleOff, kSafePoint}) {
      t += kDt;
      planner.addObservation(portAt(t, port));
      planner.notePerception(t, false);
      planner.update(t, odomAt(t, chaser));
    }
    PlannerOutput out;
    for (int i = 0; i < 4; ++i) {
      t += kDt;
      planner.addObservation(portAt(t, port));
      planner.notePerception(t, false);
      out = planner.update(t, odomAt(t, kNearContact));
    }
    ASSERT_EQ(out.state, DockingPhase::kFinal) << out.reason;
    t += kDt;
    const TrackUpdate near = planner.addObservation(portAt(t, Pose2D{0.0, 0.008, 0.01}));
    EXPECT_EQ(near.accepted, gate_on) << near.reason;
    if (!gate_on) {
      EXPECT_NE(near.reason.find("odometry-only"), std::string::npos) << near.reason;
    }
    const TrackUpdate jump = planner.addObservation(portAt(t + 0.01, Pose2D{0.0, 0.06, 0.0}));
    EXPECT_FALSE(jump.accepted);
    EXPECT_NE(jump.reason.find("odometry-only"), std::string::npos) << jump.reason;
    const TrackUpdate turned = planner.addObservation(portAt(t + 0.02, Pose2D{0.0, 0.0, 0.2}));
    EXPECT_FALSE(turned.accepted) << turned.reason;
    TargetObservation position_only = portAt(t + 0.03, port);
    position_only.orientation_valid = false;
    EXPECT_FALSE(planner.addObservation(position_only).accepted);
  }
}

TEST(ContactEstimates, NegativeGateIsRejectedByName) {
  PlannerConfig c = shippedConfig();
  c.contact_estimate_gate_m = -0.01;
  try {
    DockingPlanner p{c, shippedProbeX()};
    FAIL() << "accepted a negative gate";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("contact_estimate_gate_m"), std::string::npos);
  }
}

// Issue 12: after the clock jumps back (sim reset, bag loop), the held stamps would refuse every new
// estimate as out of order; forgetTarget() starts the track afresh and keeps the docking running.
TEST_F(StateMachineTest, ForgetTargetAcceptsEstimatesOfTheNewTimeline) {
  runFor(1.0, kFar, true);
  EXPECT_FALSE(planner_.addObservation(portAt(5.0, port_)).accepted);  // an old stamp: out of order
  planner_.forgetTarget(5.0);
  EXPECT_TRUE(planner_.active());
  const TrackUpdate update = planner_.addObservation(portAt(5.0, port_));
  EXPECT_TRUE(update.accepted) << update.reason;
  const PlannerOutput out = planner_.update(5.01, odomAt(5.01, kFar));
  EXPECT_TRUE(out.target_visible) << out.reason;
}

// What the planner reports for display (docking_msgs/PlannerGeometry): the held port and the goal it
// drives to; no goal while it stands still.
TEST_F(StateMachineTest, ReportsThePortAndTheGoalItDrivesTo) {
  PlannerOutput out = step(kFar, false);
  EXPECT_EQ(out.state, DockingPhase::kSearch);
  EXPECT_FALSE(out.goal);
  EXPECT_FALSE(out.port);
  out = step(kFar, true);
  ASSERT_EQ(out.state, DockingPhase::kApproach) << out.reason;
  ASSERT_TRUE(out.port);
  EXPECT_TRUE(out.port_orientation_known);
  EXPECT_NEAR(out.port->pose.x, port_.x, 1e-6);
  ASSERT_TRUE(out.goal);
  // APPROACH aims at a point of the safe circle.
  const double r_safe = planner_.config().law.safe_radius_m;
  EXPECT_NEAR(std::hypot(out.goal->x - port_.x, out.goal->y - port_.y), r_safe, 1e-9);
  out = step(kSafePoint, true);
  out = step(kSafePoint, true);
  ASSERT_EQ(out.state, DockingPhase::kFinal) << out.reason;
  ASSERT_TRUE(out.goal);
  // FINAL aims at the docked position: probe tip on the port centre.
  EXPECT_NEAR(out.goal->x, port_.x + planner_.probeX(), 1e-9);
  EXPECT_NEAR(out.goal->y, port_.y, 1e-9);
}
