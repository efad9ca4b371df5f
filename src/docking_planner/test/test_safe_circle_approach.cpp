// The approach law's outputs for known geometries (no state machine).
#include <gtest/gtest.h>

#include <cmath>
#include <stdexcept>

#include "docking_planner/safe_circle_approach.h"
#include "shipped_config.h"

using namespace docking_planner;

namespace {

constexpr double kTol = 1e-9;

PortState stillPort(double x, double y, double yaw) {
  PortState p;
  p.pose = Pose2D{x, y, yaw};
  return p;
}

// Distance from point p to the segment a-b.
double segmentDistance(const Vec2& a, const Vec2& b, const Vec2& p) {
  const Vec2 ab = b - a;
  const double t = std::clamp((p - a).dot(ab) / ab.squaredNorm(), 0.0, 1.0);
  return (a + t * ab - p).norm();
}

// The body-frame command turned back into odom.
Vec2 bodyToOdom(const Pose2D& chaser, const BodyTwist& t) {
  return Vec2(std::cos(chaser.yaw) * t.vx - std::sin(chaser.yaw) * t.vy,
              std::sin(chaser.yaw) * t.vx + std::cos(chaser.yaw) * t.vy);
}

}  // namespace

TEST(SafeCircleApproach, RejectsInvalidConfiguration) {
  ApproachConfig c = shippedConfig().law;
  c.safe_radius_m = 0.1;  // smaller than the probe
  EXPECT_THROW(SafeCircleApproach(c, shippedProbeX()), std::invalid_argument);
  c = shippedConfig().law;
  c.fov_margin_rad = c.camera_half_fov_rad;
  EXPECT_THROW(SafeCircleApproach(c, shippedProbeX()), std::invalid_argument);
  c = shippedConfig().law;
  c.correction_gain = NAN;
  EXPECT_THROW(SafeCircleApproach(c, shippedProbeX()), std::invalid_argument);
}

TEST(SafeCircleApproach, MeasuresErrorsWithTheDocumentedSigns) {
  const SafeCircleApproach law{shippedConfig().law, shippedProbeX()};
  const Pose2D port{0.0, 0.0, 0.0};  // port axis along odom +x
  ApproachGeometry g = law.measure(Pose2D{1.0, 0.2, M_PI}, port);
  EXPECT_NEAR(g.axial_m, 1.0, kTol);
  EXPECT_NEAR(g.lateral_m, 0.2, kTol);  // +y is the port's left
  EXPECT_NEAR(g.yaw_error_rad, 0.0, kTol);
  EXPECT_NEAR(g.polar_angle_rad, std::atan2(0.2, 1.0), kTol);
  // The chaser faces -x from y = +0.2: the port is ahead and to its left (body +y).
  EXPECT_NEAR(g.bearing_rad, std::atan2(0.2, 1.0), kTol);
  // Docked: probe tip (0.18 m ahead of base_link) on the port centre.
  g = law.measure(Pose2D{0.18, 0.0, M_PI}, port);
  EXPECT_NEAR(g.tip_error_m, 0.0, kTol);
  g = law.measure(Pose2D{0.18, 0.0, M_PI - 0.1}, port);
  EXPECT_NEAR(g.yaw_error_rad, -0.1, kTol);
  EXPECT_GT(g.tip_error_m, 0.01);
}

TEST(SafeCircleApproach, TargetStraightAheadPortFacingUsDrivesStraight) {
  const SafeCircleApproach law{shippedConfig().law, shippedProbeX()};
  const Pose2D chaser{-4.0, 0.0, 0.0};
  const PortState port = stillPort(0.0, 0.0, M_PI);  // the port looks back at the chaser
  const Vec2 goal = law.approachGoal(chaser, port.pose);
  EXPECT_NEAR(goal.x(), -0.6, kTol);
  EXPECT_NEAR(goal.y(), 0.0, kTol);
  const LawCommand cmd = law.command(Phase::kApproach, chaser, port);
  EXPECT_NEAR(cmd.twist.vx, law.config().max_speed_mps, kTol);  // far: at the speed limit
  EXPECT_NEAR(cmd.twist.vy, 0.0, kTol);
  EXPECT_NEAR(cmd.twist.wz, 0.0, kTol);
  EXPECT_FALSE(cmd.fov_limited);
  EXPECT_NEAR(cmd.goal_distance_m, 3.4, kTol);
}

TEST(SafeCircleApproach, RotatedPortPutsTheGoalInFrontOfThePort) {
  const SafeCircleApproach law{shippedConfig().law, shippedProbeX()};
  const Pose2D chaser{-4.0, 0.0, 0.0};
  const double port_yaw = M_PI - 0.5;  // turned 0.5 rad: the port axis points up-left
  const Vec2 goal = law.approachGoal(chaser, Pose2D{0.0, 0.0, port_yaw});
  EXPECT_NEAR(goal.x(), 0.6 * std::cos(port_yaw), kTol);
  EXPECT_NEAR(goal.y(), 0.6 * std::sin(port_yaw), kTol);
  // Moving there: up and forward, so the body command has vx > 0 and vy > 0 (left).
  const LawCommand cmd = law.command(Phase::kApproach, chaser, stillPort(0.0, 0.0, port_yaw));
  EXPECT_GT(cmd.twist.vx, 0.0);
  EXPECT_GT(cmd.twist.vy, 0.0);
  EXPECT_NEAR(std::atan2(cmd.twist.vy, cmd.twist.vx), std::atan2(goal.y(), goal.x() + 4.0), 1e-9);
}

TEST(SafeCircleApproach, PortFacingAwayGoesToTheTangentPointNotThroughTheCircle) {
  const SafeCircleApproach law{shippedConfig().law, shippedProbeX()};
  const Pose2D chaser{-4.0, 0.0, 0.0};
  const Pose2D port{0.0, 0.0, M_PI - 2.0};  // chaser is 2 rad (115 deg) off the port axis
  const Vec2 goal = law.approachGoal(chaser, port);
  EXPECT_NEAR(goal.norm(), 0.6, kTol);  // on the circle
  const double reach = std::acos(0.6 / 4.0) - kTangentMarginRad;
  const double goal_polar = std::atan2(goal.y(), goal.x()) - port.yaw;
  EXPECT_NEAR(goal_polar, 2.0 - reach, 1e-9);  // moved towards the axis by exactly the reach
  // The straight line to it stays outside the safe circle.
  EXPECT_GE(segmentDistance(chaser.position(), goal, port.position()), 0.6 - 1e-9);
  // The direct line to the point in front of the port would have cut through it.
  const Vec2 safe_point = 0.6 * unitAt(port.yaw);
  EXPECT_LT(segmentDistance(chaser.position(), safe_point, port.position()), 0.6);
}

TEST(SafeCircleApproach, FieldOfViewFallbackKeepsThePortInView) {
  const SafeCircleApproach law{shippedConfig().law, shippedProbeX()};
  const ApproachConfig& c = law.config();
  const Pose2D chaser{-4.0, 0.0, 0.0};
  // The docked heading would be -1.2 rad, which puts the port 1.2 rad off the camera axis.
  const Pose2D port{0.0, 0.0, M_PI - 1.2};
  bool limited = false;
  const double heading = law.desiredHeading(chaser, port, &limited);
  EXPECT_TRUE(limited);
  EXPECT_NEAR(heading, -(c.camera_half_fov_rad - c.fov_margin_rad), kTol);  // at the edge, towards the docked heading
  // With the port only slightly turned, the docked heading itself is kept.
  const double heading_small = law.desiredHeading(chaser, Pose2D{0.0, 0.0, M_PI - 0.2}, &limited);
  EXPECT_FALSE(limited);
  EXPECT_NEAR(heading_small, -0.2, kTol);
  // The yaw command turns towards it.
  EXPECT_LT(law.command(Phase::kApproach, chaser, stillPort(0.0, 0.0, M_PI - 1.2)).twist.wz, 0.0);
}

TEST(SafeCircleApproach, OnTheCircleMisalignedMovesTangentiallyTowardsTheAxis) {
  const SafeCircleApproach law{shippedConfig().law, shippedProbeX()};
  const PortState port = stillPort(1.0, 2.0, 0.3);
  for (const double gamma : {0.5, -0.5, 1.5}) {
    const Vec2 radial = unitAt(port.pose.yaw + gamma);
    const Vec2 position = port.pose.position() + 0.6 * radial;
    const Pose2D chaser{position.x(), position.y(), wrapAngle(port.pose.yaw + gamma + M_PI)};
    const LawCommand cmd = law.command(Phase::kAlign, chaser, port);
    const Vec2 increasing_gamma = perpendicular(radial);
    // Tangential, towards gamma = 0, no radial motion on the circle.
    EXPECT_LT(cmd.velocity_odom.dot(increasing_gamma) * gamma, 0.0) << "gamma " << gamma;
    EXPECT_NEAR(cmd.velocity_odom.dot(radial), 0.0, 1e-9) << "gamma " << gamma;
    EXPECT_NEAR(std::abs(cmd.velocity_odom.dot(increasing_gamma)),
                std::min(law.config().travel_gain * 0.6 * std::abs(gamma), law.config().align_speed_mps), 1e-9);
    // The body command is the same motion.
    EXPECT_TRUE(bodyToOdom(chaser, cmd.twist).isApprox(cmd.velocity_odom, 1e-9));
  }
}

TEST(SafeCircleApproach, OffTheCircleAlignPullsBackToTheRadius) {
  const SafeCircleApproach law{shippedConfig().law, shippedProbeX()};
  const PortState port = stillPort(0.0, 0.0, 0.0);
  const Pose2D outside{0.8, 0.0, M_PI};
  EXPECT_LT(law.command(Phase::kAlign, outside, port).velocity_odom.x(), 0.0);  // inwards
  const Pose2D inside{0.5, 0.0, M_PI};
  EXPECT_GT(law.command(Phase::kAlign, inside, port).velocity_odom.x(), 0.0);  // outwards
}

TEST(SafeCircleApproach, AlignedFinalGoesAlongTheAxisAndSlowsNearContact) {
  const SafeCircleApproach law{shippedConfig().law, shippedProbeX()};
  const ApproachConfig& c = law.config();
  const PortState port = stillPort(0.0, 0.0, M_PI / 2);  // port axis along odom +y
  // On the safe point, facing the port (heading -pi/2).
  const Pose2D at_safe_point{0.0, 0.6, -M_PI / 2};
  LawCommand cmd = law.command(Phase::kFinal, at_safe_point, port);
  EXPECT_NEAR(cmd.twist.vx, c.final_speed_mps, kTol);  // straight ahead, at the FINAL limit
  EXPECT_NEAR(cmd.twist.vy, 0.0, kTol);
  EXPECT_NEAR(cmd.twist.wz, 0.0, kTol);
  EXPECT_NEAR(cmd.goal.y, shippedProbeX(), kTol);  // goal: probe tip on the port
  // 3 cm from contact: slow.
  const Pose2D near_contact{0.0, shippedProbeX() + 0.03, -M_PI / 2};
  cmd = law.command(Phase::kFinal, near_contact, port);
  EXPECT_GT(cmd.twist.vx, 0.0);
  EXPECT_LE(cmd.twist.vx, kSlowZoneSpeedFraction * c.final_speed_mps + kTol);
  // Overshoot: backs out.
  const Pose2D overshoot{0.0, shippedProbeX() - 0.01, -M_PI / 2};
  EXPECT_LT(law.command(Phase::kFinal, overshoot, port).twist.vx, 0.0);
}

TEST(SafeCircleApproach, FinalFixesLateralErrorBeforeAdvancing) {
  const SafeCircleApproach law{shippedConfig().law, shippedProbeX()};
  const PortState port = stillPort(0.0, 0.0, 0.0);
  // 5 cm to the port's left (+y), beyond the lateral gate: no advance, move right.
  const Pose2D off_axis{0.4, 0.05, M_PI};
  const LawCommand cmd = law.command(Phase::kFinal, off_axis, port);
  EXPECT_NEAR(cmd.velocity_odom.x(), 0.0, kTol);
  EXPECT_LT(cmd.velocity_odom.y(), 0.0);
  // Half the gate: advances at reduced speed.
  const Pose2D half_gate{0.4, 0.015, M_PI};
  const LawCommand half = law.command(Phase::kFinal, half_gate, port);
  EXPECT_LT(half.velocity_odom.x(), 0.0);
  EXPECT_GT(half.velocity_odom.x(), -law.config().final_speed_mps + 1e-6);
}

TEST(SafeCircleApproach, RotatingPortIsFedForward) {
  const SafeCircleApproach law{shippedConfig().law, shippedProbeX()};
  PortState port = stillPort(0.0, 0.0, 0.0);
  port.yaw_rate = 0.05;
  port.velocity = Vec2(0.0, 0.01);
  // Exactly docked: the only motion commanded is the port's own (a point of its frame at the chaser).
  const Pose2D docked{law.probeX(), 0.0, M_PI};
  const LawCommand cmd = law.command(Phase::kFinal, docked, port);
  const Vec2 expected = port.velocity + port.yaw_rate * perpendicular(docked.position() - port.pose.position());
  EXPECT_TRUE(cmd.velocity_odom.isApprox(expected, 1e-12));
  EXPECT_NEAR(cmd.twist.wz, 0.05, kTol);
}

TEST(SafeCircleApproach, BackOffMovesRadiallyOutToTheCircleOnly) {
  const SafeCircleApproach law{shippedConfig().law, shippedProbeX()};
  const PortState port = stillPort(0.0, 0.0, 0.0);
  const LawCommand inside = law.command(Phase::kBackOff, Pose2D{0.3, 0.1, M_PI}, port);
  EXPECT_GT(inside.velocity_odom.dot(Vec2(0.3, 0.1).normalized()), 0.0);
  EXPECT_NEAR(inside.velocity_odom.dot(perpendicular(Vec2(0.3, 0.1).normalized())), 0.0, 1e-12);
  const LawCommand outside = law.command(Phase::kBackOff, Pose2D{0.9, 0.0, M_PI}, port);
  EXPECT_NEAR(outside.velocity_odom.norm(), 0.0, kTol);
}

TEST(SafeCircleApproach, PlannedPathEndsDockedAndPassesTheSafePoint) {
  const SafeCircleApproach law{shippedConfig().law, shippedProbeX()};
  const Pose2D port{0.0, 0.0, M_PI - 1.0};
  const Pose2D chaser{-4.0, 0.5, 0.0};
  const auto path = law.plannedPath(Phase::kApproach, chaser, port);
  ASSERT_GE(path.size(), 4u);
  EXPECT_NEAR(path.front().x, chaser.x, kTol);
  const Vec2 docked = law.dockedPosition(port);
  EXPECT_NEAR(path.back().x, docked.x(), kTol);
  EXPECT_NEAR(path.back().y, docked.y(), kTol);
  const Vec2 safe_point = 0.6 * unitAt(port.yaw);
  const auto& before_last = path[path.size() - 2];
  EXPECT_NEAR(before_last.x, safe_point.x(), 1e-9);
  EXPECT_NEAR(before_last.y, safe_point.y(), 1e-9);
  // Every arc point is on the safe circle.
  for (std::size_t i = 1; i + 1 < path.size(); ++i) EXPECT_NEAR(path[i].position().norm(), 0.6, 1e-9);
}
