#include <gtest/gtest.h>

#include <cmath>

#include "omni_base/velocity_limiter.h"

using omni_base::AxisLimits;
using omni_base::Twist2D;
using omni_base::VelocityLimiter;

namespace {
AxisLimits limits() {
  AxisLimits l;
  l.max_velocity = {0.4, 0.4, 1.5};
  l.max_acceleration = {0.8, 0.8, 3.0};
  return l;
}
}  // namespace

TEST(VelocityLimiter, KeepsDirectionWhenOneAxisSaturates) {
  const VelocityLimiter limiter(limits());
  const Twist2D out = limiter.limitVelocity(Twist2D{1.0, 0.2, 0.3});
  EXPECT_NEAR(out.vx, 0.4, 1e-12);
  // Same ratios as the command: the direction and the curvature are kept.
  EXPECT_NEAR(out.vy / out.vx, 0.2, 1e-12);
  EXPECT_NEAR(out.wz / out.vx, 0.3, 1e-12);
}

TEST(VelocityLimiter, LeavesCommandsInsideTheLimitsAlone) {
  const VelocityLimiter limiter(limits());
  const Twist2D out = limiter.limitVelocity(Twist2D{0.1, -0.2, 0.5});
  EXPECT_DOUBLE_EQ(out.vx, 0.1);
  EXPECT_DOUBLE_EQ(out.vy, -0.2);
  EXPECT_DOUBLE_EQ(out.wz, 0.5);
}

TEST(VelocityLimiter, AccelerationLimitRampsAlongTheCommandedDirection) {
  const VelocityLimiter limiter(limits());
  Twist2D current;
  const Twist2D target{0.3, 0.3, 0.0};
  const double dt = 0.02;
  int steps = 0;
  while ((std::abs(current.vx - target.vx) > 1e-9) && steps < 1000) {
    const Twist2D next = limiter.limit(current, target, dt);
    EXPECT_LE(std::abs(next.vx - current.vx), 0.8 * dt + 1e-12);
    EXPECT_LE(std::abs(next.vy - current.vy), 0.8 * dt + 1e-12);
    EXPECT_NEAR(next.vx, next.vy, 1e-12);  // diagonal command stays diagonal during the ramp
    current = next;
    ++steps;
  }
  // 0.3 m/s at 0.8 m/s^2 takes 0.375 s: 19 steps of 20 ms.
  EXPECT_EQ(steps, 19);
}

TEST(VelocityLimiter, WheelSaturationScalesAllWheelsTogether) {
  std::vector<double> wheels{30.0, -10.0, 5.0};
  const double scale = omni_base::saturateWheelSpeeds(wheels, 20.0);
  EXPECT_NEAR(scale, 2.0 / 3.0, 1e-12);
  EXPECT_NEAR(wheels[0], 20.0, 1e-12);
  EXPECT_NEAR(wheels[1] / wheels[0], -10.0 / 30.0, 1e-12);
  EXPECT_NEAR(wheels[2] / wheels[0], 5.0 / 30.0, 1e-12);
  std::vector<double> slow{1.0, 2.0, -3.0};
  EXPECT_DOUBLE_EQ(omni_base::saturateWheelSpeeds(slow, 20.0), 1.0);
  EXPECT_DOUBLE_EQ(slow[2], -3.0);
}

TEST(VelocityLimiter, RejectsNonPositiveLimits) {
  AxisLimits bad = limits();
  bad.max_velocity[2] = 0.0;
  EXPECT_THROW(VelocityLimiter{bad}, std::invalid_argument);
  bad = limits();
  bad.max_acceleration[0] = NAN;
  EXPECT_THROW(VelocityLimiter{bad}, std::invalid_argument);
}
