#include <gtest/gtest.h>

#include <cmath>

#include "omni_base/base_controller.h"

using namespace omni_base;

namespace {

OmniKinematics kinematics() { return OmniKinematics({{0.0, 2.0 * M_PI / 3.0, 4.0 * M_PI / 3.0}, 0.10, 0.024}); }

BaseControllerConfig config() {
  BaseControllerConfig c;
  c.limits.max_velocity = {0.4, 0.4, 1.5};
  c.limits.max_acceleration = {0.8, 0.8, 3.0};
  c.stop_deceleration = {5.0, 5.0, 15.0};
  c.cmd_timeout_s = 0.5;
  c.max_wheel_speed_rad_s = 20.0;
  return c;
}

double maxWheel(const BaseController::Output& out) {
  double m = 0.0;
  for (double w : out.wheel_rad_s) m = std::max(m, std::abs(w));
  return m;
}

// Runs the controller at 50 Hz from t0 to t1, sending `cmd` every cycle when `send` is set.
BaseController::Output run(BaseController& c, double t0, double t1, const Twist2D& cmd, bool send) {
  BaseController::Output out;
  for (double t = t0; t < t1 - 1e-9; t += 0.02) {
    if (send) c.command(cmd, t);
    out = c.update(t, true);
  }
  return out;
}

}  // namespace

TEST(BaseController, StaysStillUntilTheFirstCommand) {
  BaseController c(kinematics(), config());
  const auto out = c.update(0.0, true);
  EXPECT_EQ(out.stop_reason, StopReason::kNoCommand);
  EXPECT_EQ(maxWheel(out), 0.0);
}

TEST(BaseController, FollowsACommandAfterTheAccelerationRamp) {
  BaseController c(kinematics(), config());
  const auto out = run(c, 0.0, 1.0, Twist2D{0.2, 0.0, 0.0}, true);
  EXPECT_EQ(out.stop_reason, StopReason::kNone);
  EXPECT_NEAR(out.body.vx, 0.2, 1e-9);
  EXPECT_NEAR(out.wheel_rad_s[0], 0.2 / 0.024, 1e-9);
}

TEST(BaseController, WatchdogStopsTheBaseAfterTheTimeout) {
  BaseController c(kinematics(), config());
  run(c, 0.0, 1.0, Twist2D{0.2, 0.0, 0.0}, true);  // last command at t = 0.98
  auto out = run(c, 1.0, 1.46, Twist2D{}, false);   // still within 0.5 s of it
  EXPECT_NEAR(out.body.vx, 0.2, 1e-9);
  EXPECT_EQ(c.watchdogTrips(), 0u);
  out = run(c, 1.46, 1.60, Twist2D{}, false);       // timed out at 1.48, stop deceleration 5 m/s^2
  EXPECT_EQ(out.stop_reason, StopReason::kWatchdog);
  EXPECT_EQ(maxWheel(out), 0.0);
  EXPECT_EQ(c.watchdogTrips(), 1u);
}

TEST(BaseController, ZeroCommandStopsAtTheStopDeceleration) {
  BaseController c(kinematics(), config());
  run(c, 0.0, 1.0, Twist2D{0.3, 0.0, 0.0}, true);
  // At the ramp's 0.8 m/s^2, 0.3 m/s would take 0.375 s to stop; a zero command is a stop: 5 m/s^2.
  auto out = run(c, 1.0, 1.08, Twist2D{}, true);
  EXPECT_EQ(out.stop_reason, StopReason::kNone);
  EXPECT_EQ(maxWheel(out), 0.0);
  // A small non-zero command still ramps at max_acceleration.
  run(c, 1.08, 2.0, Twist2D{0.3, 0.0, 0.0}, true);
  out = run(c, 2.0, 2.1, Twist2D{0.01, 0.0, 0.0}, true);
  EXPECT_GT(out.body.vx, 0.15);
}

TEST(BaseController, NonFiniteCommandsAreRejectedAndDoNotFeedTheWatchdog) {
  BaseController c(kinematics(), config());
  EXPECT_EQ(c.command(Twist2D{NAN, 0.0, 0.0}, 0.0), CommandVerdict::kRejectedNonFinite);
  EXPECT_EQ(c.command(Twist2D{0.1, INFINITY, 0.0}, 0.0), CommandVerdict::kRejectedNonFinite);
  auto out = c.update(0.0, true);
  EXPECT_EQ(maxWheel(out), 0.0);
  run(c, 0.0, 1.0, Twist2D{0.2, 0.0, 0.0}, true);
  // A stream of NaN after good commands: the base must stop at the timeout, not keep going.
  out = run(c, 1.0, 2.0, Twist2D{NAN, NAN, NAN}, true);
  EXPECT_EQ(out.stop_reason, StopReason::kWatchdog);
  EXPECT_EQ(maxWheel(out), 0.0);
  EXPECT_EQ(c.rejectedCommands(), 2u + 50u);
}

TEST(BaseController, EStopLatchesUntilReleasedAndANewCommandArrives) {
  BaseController c(kinematics(), config());
  run(c, 0.0, 1.0, Twist2D{0.2, 0.0, 0.0}, true);
  c.engageEStop();
  auto out = run(c, 1.0, 2.0, Twist2D{0.2, 0.0, 0.0}, true);  // commands keep coming: ignored
  EXPECT_EQ(out.stop_reason, StopReason::kEStop);
  EXPECT_EQ(maxWheel(out), 0.0);
  c.releaseEStop(2.0);
  out = c.update(2.0, true);
  EXPECT_EQ(maxWheel(out), 0.0);  // released, but the old command is gone
  out = run(c, 2.02, 3.0, Twist2D{0.2, 0.0, 0.0}, true);
  EXPECT_EQ(out.stop_reason, StopReason::kNone);
  EXPECT_NEAR(out.body.vx, 0.2, 1e-9);
}

TEST(BaseController, LinkDownCommandsZero) {
  BaseController c(kinematics(), config());
  run(c, 0.0, 1.0, Twist2D{0.2, 0.0, 0.0}, true);
  c.command(Twist2D{0.2, 0.0, 0.0}, 1.0);
  const auto out = c.update(1.0, false);
  EXPECT_EQ(out.stop_reason, StopReason::kLinkDown);
  EXPECT_EQ(maxWheel(out), 0.0);
}

TEST(BaseController, WheelSaturationKeepsTheDirection) {
  BaseControllerConfig cfg = config();
  cfg.max_wheel_speed_rad_s = 10.0;  // lower than 0.4 m/s needs on wheel 0 (16.7 rad/s)
  BaseController c(kinematics(), cfg);
  const auto out = run(c, 0.0, 2.0, Twist2D{0.4, 0.1, 0.0}, true);
  EXPECT_LT(out.wheel_saturation_scale, 1.0);
  EXPECT_NEAR(maxWheel(out), 10.0, 1e-9);
  EXPECT_NEAR(out.body.vy / out.body.vx, 0.25, 1e-9);
  EXPECT_NEAR(out.body.wz, 0.0, 1e-12);
}

TEST(BaseController, TimeGoingBackwardsRestartsFromRest) {
  BaseController c(kinematics(), config());
  run(c, 10.0, 11.0, Twist2D{0.2, 0.0, 0.0}, true);
  const auto out = c.update(0.5, true);  // a bag looped
  EXPECT_EQ(out.stop_reason, StopReason::kNoCommand);
  EXPECT_EQ(maxWheel(out), 0.0);
}

