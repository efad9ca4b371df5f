#include <gtest/gtest.h>

#include <cmath>

#include "omni_base/kinematics.h"
#include "omni_base/odometry.h"

using omni_base::OdometryIntegrator;
using omni_base::Twist2D;

TEST(Odometry, StraightLineAlongHeading) {
  OdometryIntegrator odom;
  odom.reset({1.0, 2.0, M_PI / 2});
  for (int i = 0; i < 100; ++i) odom.integrate(Twist2D{0.2, 0.0, 0.0}, 0.02);
  EXPECT_NEAR(odom.pose().x, 1.0, 1e-12);
  EXPECT_NEAR(odom.pose().y, 2.4, 1e-12);
  EXPECT_NEAR(odom.pose().yaw, M_PI / 2, 1e-12);
}

TEST(Odometry, ExactArcClosesAFullCircleInOneStepOrMany) {
  // v = 0.2 m/s, w = 0.5 rad/s: a circle of radius 0.4 m closes after 4 pi s. Exact-arc integration
  // returns to the start whatever the step, even in one single step of a quarter turn.
  for (int steps : {4, 125, 1250}) {
    const double dt = 4.0 * M_PI / steps;
    OdometryIntegrator odom;
    for (int i = 0; i < steps; ++i) odom.integrate(Twist2D{0.2, 0.0, 0.5}, dt);
    EXPECT_NEAR(odom.pose().x, 0.0, 1e-9) << "dt " << dt;
    EXPECT_NEAR(odom.pose().y, 0.0, 1e-9) << "dt " << dt;
  }
  // Half a turn: the robot is 0.8 m to the left, facing back.
  OdometryIntegrator odom;
  odom.integrate(Twist2D{0.2, 0.0, 0.5}, 2.0 * M_PI);
  EXPECT_NEAR(odom.pose().x, 0.0, 1e-9);
  EXPECT_NEAR(odom.pose().y, 0.8, 1e-9);
  EXPECT_NEAR(std::abs(odom.pose().yaw), M_PI, 1e-9);
}

TEST(Odometry, KnownWheelSpeedHistory) {
  // The paper's layout; one second of pure +y, then a quarter turn in place, then one second of +x.
  const omni_base::OmniKinematics k({{0.0, 2.0 * M_PI / 3.0, 4.0 * M_PI / 3.0}, 0.10, 0.024});
  OdometryIntegrator odom;
  const double dt = 0.02;
  auto run = [&](const Twist2D& body, double seconds) {
    const auto wheels = k.inverse(body);  // what the encoders would report
    for (int i = 0; i < static_cast<int>(std::round(seconds / dt)); ++i) odom.integrate(k.forward(wheels), dt);
  };
  run(Twist2D{0.0, 0.3, 0.0}, 1.0);
  run(Twist2D{0.0, 0.0, M_PI / 2.0}, 1.0);
  run(Twist2D{0.1, 0.0, 0.0}, 1.0);
  // After the quarter turn, body +x points along odom +y.
  EXPECT_NEAR(odom.pose().x, 0.0, 1e-9);
  EXPECT_NEAR(odom.pose().y, 0.4, 1e-9);
  EXPECT_NEAR(odom.pose().yaw, M_PI / 2.0, 1e-9);
}

TEST(Odometry, IgnoresNonFiniteInput) {
  OdometryIntegrator odom;
  odom.integrate(Twist2D{NAN, 0.0, 0.0}, 0.1);
  odom.integrate(Twist2D{0.1, 0.0, 0.0}, -1.0);
  EXPECT_EQ(odom.pose().x, 0.0);
  EXPECT_EQ(odom.pose().y, 0.0);
}

TEST(Odometry, NormalizeAngle) {
  EXPECT_NEAR(omni_base::normalizeAngle(3.0 * M_PI), M_PI, 1e-12);
  EXPECT_NEAR(omni_base::normalizeAngle(-M_PI / 2 - 2 * M_PI), -M_PI / 2, 1e-12);
  EXPECT_NEAR(omni_base::normalizeAngle(0.1), 0.1, 1e-12);
}
