// The simulated omni base: motor lag, kinematics, exact integration, encoders, rejection, watchdog.
#include <gtest/gtest.h>

#include <cmath>

#include "docking_sim/chaser_base.h"
#include "docking_sim/configs.h"
#include "omni_base/kinematics.h"
#include "test_helpers.h"

using docking_sim::ChaserBase;
using docking_sim::CommandResult;

namespace {

docking_sim::OmniBaseModel model() {
  return docking_sim::loadOmniBaseModel(docking_sim_test::configDir() + "/omni_base.yaml");
}

/// Drives the base at a body twist for duration_s with commands re-sent every 20 ms.
void drive(ChaserBase& base, const omni_base::Twist2D& twist, double duration_s, double* now) {
  const omni_base::OmniKinematics kin(model().layout);
  const double dt = 0.005;
  for (int k = 0; k < static_cast<int>(std::round(duration_s / dt)); ++k) {
    if (k % 4 == 0) {
      ASSERT_EQ(base.command(true, kin.inverse(twist), *now), CommandResult::kAccepted);
    }
    base.step(*now, dt);
    *now += dt;
  }
}

}  // namespace

TEST(ChaserBase, StraightLineFollowsTheFirstOrderMotorLag) {
  const auto m = model();
  ChaserBase base(m, 0.25, omni_base::Pose2D{});
  double now = 0.0;
  const double v = 0.2, T = 2.0, tau = m.motor_time_constant_s;
  drive(base, {v, 0.0, 0.0}, T, &now);
  // Distance of a first-order response to a step: v (T - tau (1 - exp(-T/tau))).
  EXPECT_NEAR(base.pose().x, v * (T - tau * (1 - std::exp(-T / tau))), 1e-9);
  EXPECT_NEAR(base.pose().y, 0.0, 1e-9);
  EXPECT_NEAR(base.twist().vx, v, 1e-9);
}

TEST(ChaserBase, ArcIsIntegratedExactly) {
  ChaserBase base(model(), 0.25, omni_base::Pose2D{});
  double now = 0.0;
  const double v = 0.2, w = 0.5;
  drive(base, {v, 0.0, w}, 4.0, &now);
  // After the lag has died out the base runs on a circle of radius v/w; the lag only shifts it
  // along the circle: the distance from the circle's centre must be v/w.
  const double cx = 0.0, cy = v / w;
  EXPECT_NEAR(std::hypot(base.pose().x - cx, base.pose().y - cy), v / w, 1e-6);
  const double tau = model().motor_time_constant_s;
  EXPECT_NEAR(base.pose().yaw, std::remainder(w * (4.0 - tau * (1 - std::exp(-4.0 / tau))), 2 * M_PI), 1e-9);
}

TEST(ChaserBase, EncoderCountsFollowTheWheelAngles) {
  const auto m = model();
  ChaserBase base(m, 0.25, omni_base::Pose2D{});
  double now = 0.0;
  drive(base, {0.1, -0.05, 0.3}, 1.0, &now);
  const auto counts = base.encoderCounts();
  ASSERT_EQ(counts.size(), 3u);
  for (std::size_t i = 0; i < 3; ++i) {
    EXPECT_NEAR(counts[i], base.wheelAngles()[i] * m.encoder_counts_per_rev / (2 * M_PI), 1.0);
    EXPECT_NE(counts[i], 0);
  }
}

TEST(ChaserBase, NonFiniteCommandsAreRejectedAndNeverIntegrated) {
  ChaserBase base(model(), 0.25, omni_base::Pose2D{});
  double now = 0.0;
  drive(base, {0.2, 0.0, 0.0}, 0.5, &now);
  EXPECT_EQ(base.command(true, {NAN, 1.0, 1.0}, now), CommandResult::kRejectedNonFinite);
  EXPECT_EQ(base.command(true, {1.0, INFINITY, 1.0}, now), CommandResult::kRejectedNonFinite);
  EXPECT_EQ(base.command(true, {1.0, 1.0}, now), CommandResult::kRejectedWrongSize);
  for (int k = 0; k < 200; ++k) {
    base.step(now, 0.005);
    now += 0.005;
  }
  // The set-points went to zero: the base coasts to a stop (within the lag), never to NaN.
  EXPECT_TRUE(std::isfinite(base.pose().x));
  EXPECT_NEAR(base.twist().vx, 0.0, 1e-9);
  EXPECT_LT(base.pose().x, 0.2 * 0.5 + 0.01);
}

TEST(ChaserBase, StaleOrDisabledCommandsStopTheWheels) {
  const auto m = model();
  const omni_base::OmniKinematics kin(m.layout);
  ChaserBase base(m, 0.25, omni_base::Pose2D{});
  double now = 0.0;
  base.command(true, kin.inverse({0.2, 0, 0}), now);
  for (int k = 0; k < 40; ++k, now += 0.005) base.step(now, 0.005);  // 0.2 s: still fresh
  EXPECT_NEAR(base.twist().vx, 0.2, 1e-3);
  for (int k = 0; k < 60; ++k, now += 0.005) base.step(now, 0.005);  // 0.5 s: stale after 0.25 s
  EXPECT_NEAR(base.twist().vx, 0.0, 1e-3);

  base.command(false, kin.inverse({0.2, 0, 0}), now);
  for (int k = 0; k < 40; ++k, now += 0.005) base.step(now, 0.005);
  EXPECT_NEAR(base.twist().vx, 0.0, 1e-9);
  EXPECT_FALSE(base.motorsEnabled());
}
