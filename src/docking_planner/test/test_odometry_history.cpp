// OdometryHistory: the chaser's pose at an image stamp, interpolated or advanced along the twist.
#include <gtest/gtest.h>

#include <cmath>

#include "docking_planner/odometry_history.h"

namespace docking_planner {
namespace {

// An omni chaser on a circle: forward at v with yaw rate w (its exact pose at any time).
Pose2D onCircle(double t, double v, double w) {
  const double r = v / w;
  return Pose2D{r * std::sin(w * t), r * (1.0 - std::cos(w * t)), wrapAngle(w * t)};
}

TEST(AdvanceAlongTwist, FollowsTheExactArc) {
  const double v = 0.3, w = 0.8;
  const Pose2D start = onCircle(1.0, v, w);
  const Pose2D moved = advanceAlongTwist(start, BodyTwist{v, 0.0, w}, 0.5);
  const Pose2D truth = onCircle(1.5, v, w);
  EXPECT_NEAR(moved.x, truth.x, 1e-12);
  EXPECT_NEAR(moved.y, truth.y, 1e-12);
  EXPECT_NEAR(moved.yaw, truth.yaw, 1e-12);
}

TEST(AdvanceAlongTwist, SidewaysWithoutTurningIsAStraightLine) {
  const Pose2D moved = advanceAlongTwist(Pose2D{1.0, 2.0, M_PI / 2}, BodyTwist{0.0, 0.2, 0.0}, 2.0);
  EXPECT_NEAR(moved.x, 1.0 - 0.4, 1e-12);  // body +y is odom -x when facing +y
  EXPECT_NEAR(moved.y, 2.0, 1e-12);
  EXPECT_NEAR(moved.yaw, M_PI / 2, 1e-12);
}

TEST(OdometryHistory, InterpolatesBetweenSamplesAndAcrossTheYawWrap) {
  OdometryHistory h;
  ASSERT_TRUE(h.add(OdometrySample{10.0, Pose2D{0.0, 0.0, M_PI - 0.1}, BodyTwist{}}));
  ASSERT_TRUE(h.add(OdometrySample{10.1, Pose2D{0.02, -0.04, -M_PI + 0.1}, BodyTwist{}}));
  const auto p = h.poseAt(10.025, 0.0);
  ASSERT_TRUE(p.has_value());
  EXPECT_NEAR(p->x, 0.005, 1e-12);
  EXPECT_NEAR(p->y, -0.01, 1e-12);
  EXPECT_NEAR(p->yaw, M_PI - 0.05, 1e-12);  // along the short arc through pi, not back through 0
}

TEST(OdometryHistory, AdvancesTheNewestSampleOnlyWithinTheLimit) {
  const double v = 0.25, w = -0.6;
  OdometryHistory h;
  for (int i = 0; i <= 10; ++i) h.add(OdometrySample{0.01 * i, onCircle(0.01 * i, v, w), BodyTwist{v, 0.0, w}});
  const auto ahead = h.poseAt(0.13, 0.05);
  ASSERT_TRUE(ahead.has_value());
  const Pose2D truth = onCircle(0.13, v, w);
  EXPECT_NEAR(ahead->x, truth.x, 1e-9);
  EXPECT_NEAR(ahead->y, truth.y, 1e-9);
  EXPECT_NEAR(ahead->yaw, truth.yaw, 1e-9);
  EXPECT_FALSE(h.poseAt(0.16, 0.05).has_value());  // 60 ms past the newest: wait for odometry instead
  EXPECT_FALSE(h.poseAt(-0.01, 0.05).has_value());  // older than the history
}

TEST(OdometryHistory, RejectsNonFiniteAndOutOfOrderSamplesAndForgetsOldOnes) {
  OdometryHistory h(1.0);
  EXPECT_TRUE(h.add(OdometrySample{0.0, Pose2D{}, BodyTwist{}}));
  EXPECT_FALSE(h.add(OdometrySample{0.0, Pose2D{1.0, 0.0, 0.0}, BodyTwist{}}));
  EXPECT_FALSE(h.add(OdometrySample{0.5, Pose2D{NAN, 0.0, 0.0}, BodyTwist{}}));
  EXPECT_FALSE(h.add(OdometrySample{0.5, Pose2D{}, BodyTwist{0.0, INFINITY, 0.0}}));
  EXPECT_EQ(h.size(), 1u);
  for (int i = 1; i <= 30; ++i) EXPECT_TRUE(h.add(OdometrySample{0.1 * i, Pose2D{0.1 * i, 0.0, 0.0}, BodyTwist{}}));
  EXPECT_FALSE(h.poseAt(1.5, 0.0).has_value());  // older than 1 s before the newest (3.0 s): dropped
  const auto p = h.poseAt(2.55, 0.0);
  ASSERT_TRUE(p.has_value());
  EXPECT_NEAR(p->x, 2.55, 1e-9);
}

}  // namespace
}  // namespace docking_planner
