// The port held in odom: velocities from successive poses, prediction, rejected inputs.
#include <gtest/gtest.h>

#include <cmath>

#include "docking_planner/target_track.h"

using namespace docking_planner;

namespace {

TargetObservation observe(double t, double x, double y, double yaw) {
  TargetObservation o;
  o.stamp_s = t;
  o.valid = true;
  o.orientation_valid = true;
  o.pose = Pose2D{x, y, yaw};
  return o;
}

// A port 0.15 m ahead of a target turning about (2, 1) at `rate` rad/s.
TargetObservation rotatingPort(double t, double rate) {
  const double yaw = 0.4 + rate * t;
  return observe(t, 2.0 + 0.15 * std::cos(yaw), 1.0 + 0.15 * std::sin(yaw), yaw);
}

}  // namespace

TEST(TargetTrack, StillTargetHasNoVelocityAndPredictsInPlace) {
  TargetTrack track{TrackConfig{}};
  for (int i = 0; i < 30; ++i) ASSERT_TRUE(track.update(observe(0.1 * i, 1.0, -0.5, 2.0)).accepted);
  const PortState p = track.predict(2.9 + 1.0);
  EXPECT_NEAR(p.velocity.norm(), 0.0, 1e-12);
  EXPECT_NEAR(p.yaw_rate, 0.0, 1e-12);
  EXPECT_NEAR(p.pose.x, 1.0, 1e-12);
  EXPECT_NEAR(p.pose.yaw, 2.0, 1e-12);
}

TEST(TargetTrack, RotatingTargetRateFromSuccessivePoses) {
  const double rate = 3.0 * M_PI / 180.0;  // 3 deg/s
  TargetTrack track{TrackConfig{}};
  for (int i = 0; i <= 100; ++i) ASSERT_TRUE(track.update(rotatingPort(0.1 * i, rate)).accepted);
  const PortState now = track.predict(10.0);
  EXPECT_NEAR(now.yaw_rate, rate, 0.02 * rate);
  EXPECT_NEAR(now.velocity.norm(), 0.15 * rate, 0.05 * 0.15 * rate);
  // Held for 2 s without estimates: the prediction follows the truth to within a few mm.
  const PortState later = track.predict(12.0);
  const TargetObservation truth = rotatingPort(12.0, rate);
  EXPECT_NEAR(later.pose.yaw, truth.pose.yaw, 0.002);
  EXPECT_NEAR((later.pose.position() - truth.pose.position()).norm(), 0.0, 0.003);
}

TEST(TargetTrack, PrefersTheEstimateYawRateWhenGiven) {
  TargetTrack track{TrackConfig{}};
  for (int i = 0; i <= 50; ++i) {
    TargetObservation o = observe(0.1 * i, 0.0, 0.0, 0.0);  // pose does not turn...
    o.yaw_rate_valid = true;
    o.yaw_rate = 0.1;  // ...but the twist says it does
    ASSERT_TRUE(track.update(o).accepted);
  }
  EXPECT_NEAR(track.predict(5.0).yaw_rate, 0.1, 1e-3);
  TrackConfig poses_only;
  poses_only.use_estimate_yaw_rate = false;
  TargetTrack differencing{poses_only};
  for (int i = 0; i <= 50; ++i) {
    TargetObservation o = observe(0.1 * i, 0.0, 0.0, 0.0);
    o.yaw_rate_valid = true;
    o.yaw_rate = 0.1;
    ASSERT_TRUE(differencing.update(o).accepted);
  }
  EXPECT_NEAR(differencing.predict(5.0).yaw_rate, 0.0, 1e-12);
}

TEST(TargetTrack, RejectsNanOutOfOrderAndInvalid) {
  TargetTrack track{TrackConfig{}};
  ASSERT_TRUE(track.update(observe(1.0, 1.0, 1.0, 0.0)).accepted);
  TrackUpdate u = track.update(observe(1.1, NAN, 1.0, 0.0));
  EXPECT_FALSE(u.accepted);
  EXPECT_NE(u.reason.find("NaN"), std::string::npos);
  u = track.update(observe(0.9, 5.0, 5.0, 0.0));
  EXPECT_FALSE(u.accepted);
  EXPECT_NE(u.reason.find("out of order"), std::string::npos);
  TargetObservation invalid = observe(1.2, 5.0, 5.0, 0.0);
  invalid.valid = false;
  invalid.status = "no contour";
  u = track.update(invalid);
  EXPECT_FALSE(u.accepted);
  EXPECT_NE(u.reason.find("no contour"), std::string::npos);
  // The held pose is the first one.
  EXPECT_NEAR(track.predict(1.2).pose.x, 1.0, 1e-12);
  EXPECT_DOUBLE_EQ(track.lastStamp(), 1.0);
}

TEST(TargetTrack, PositionOnlyEstimateKeepsTheHeldPortAxis) {
  TargetTrack track{TrackConfig{}};
  ASSERT_TRUE(track.update(observe(1.0, 1.0, 1.0, 0.7)).accepted);
  TargetObservation position_only = observe(1.1, 1.2, 1.0, 99.0);
  position_only.orientation_valid = false;
  ASSERT_TRUE(track.update(position_only).accepted);
  const PortState p = track.predict(1.1);
  EXPECT_NEAR(p.pose.x, 1.2, 1e-12);
  EXPECT_NEAR(p.pose.yaw, 0.7, 1e-12);
  EXPECT_DOUBLE_EQ(track.lastOrientationStamp(), 1.0);
}

TEST(TargetTrack, NoVelocitySpikeWhenTheSourceChanges) {
  TargetTrack track{TrackConfig{}};
  for (int i = 0; i < 10; ++i) ASSERT_TRUE(track.update(observe(0.1 * i, 1.0, 0.0, 0.0)).accepted);
  TargetObservation other = observe(1.0, 1.05, 0.0, 0.0);  // another source, biased by 5 cm
  other.source = 2;
  ASSERT_TRUE(track.update(other).accepted);
  EXPECT_NEAR(track.predict(1.0).velocity.norm(), 0.0, 1e-12);
}
