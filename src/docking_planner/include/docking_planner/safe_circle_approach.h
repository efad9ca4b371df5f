// The paper's approach law (section III.C), on an omni base, in the odom frame. ROS-free.
//
//  APPROACH  straight to the point on the safe circle in front of the docking port. When that point
//            cannot be reached in a straight line without cutting into the circle, the goal is the
//            circle point nearest to it that can (the tangent point); the rest is done on the arc.
//  ALIGN     circular motion on the safe circle until on the port axis (tangential speed ~ R * gamma,
//            the paper's v_x ~ SafeDistance * theta), holding the radius.
//  FINAL     along the port axis until the probe tip touches the port centre: slow, and slower still
//            near contact; lateral and heading errors are closed first.
//  BACK_OFF  radially out to the safe circle (ABORT).
// Heading, all phases: the chaser turns towards the docked heading (x along the reversed port axis,
// the paper's omega ~ theta), but never so far that the port leaves the camera's field of view: when
// it would, the heading is held at the edge of the view, pointing at the port ("aim as if
// beta = theta", the paper's fallback).
// Moving target: the port's velocity and angular velocity are fed forward, so that in the port's own
// frame the chaser sees a still target.
#pragma once

#include <string>
#include <vector>

#include "docking_planner/planar.h"
#include "docking_planner/planner_settings.h"

namespace docking_planner {

/// The straight approach stays this far outside the tangent to the safe circle, rad (a constant of the
/// law).
constexpr double kTangentMarginRad = 0.05;
/// FINAL's speed with the probe tip within final_slow_distance_m of the port, as a fraction of
/// final_speed_mps, so that one speed sets both: half (0.04 of 0.08 m/s).
constexpr double kSlowZoneSpeedFraction = 0.5;

/// The settings (settings/planner.yaml) and what one range cannot say; throws naming the bad field.
void validate(const ApproachConfig& config);

/// The docking port in odom: pose, and its velocity (of the port centre) and angular velocity.
struct PortState {
  Pose2D pose;                 ///< origin at the port centre, yaw = direction of the port axis (out of the face)
  Vec2 velocity{Vec2::Zero()}; ///< m/s, odom
  double yaw_rate{0.0};        ///< rad/s
};

/// Where the chaser is relative to the port (the errors DockingState reports).
struct ApproachGeometry {
  double range_m{0.0};           ///< base_link to the port centre
  double polar_angle_rad{0.0};   ///< gamma (the paper's beta): port axis to the line port -> chaser
  double lateral_m{0.0};         ///< base_link off the port axis, + to the port's left (target y)
  double axial_m{0.0};           ///< base_link along the port axis from the face
  double yaw_error_rad{0.0};     ///< chaser heading minus the docked heading (port yaw + pi)
  double bearing_rad{0.0};       ///< alpha: chaser x axis to the line base_link -> port
  double tip_error_m{0.0};       ///< probe tip to the port centre (0 when docked)
};

enum class Phase { kApproach, kAlign, kFinal, kBackOff };
const char* phaseName(Phase phase);

struct LawCommand {
  BodyTwist twist;               ///< base_link command
  Vec2 velocity_odom{Vec2::Zero()};
  Pose2D goal;                   ///< this phase's goal (position and heading), odom
  double goal_distance_m{0.0};   ///< base_link to goal.position
  bool fov_limited{false};       ///< the heading was held at the edge of the field of view
};

class SafeCircleApproach {
 public:
  /// probe_x_m: the docking probe tip on base_link +x (robot data: config/robot.yaml's
  /// chaser.docking_probe_x_m), inside the safe circle. Throws std::invalid_argument for an invalid
  /// configuration.
  SafeCircleApproach(const ApproachConfig& config, double probe_x_m);

  const ApproachConfig& config() const { return config_; }
  double probeX() const { return probe_x_m_; }

  ApproachGeometry measure(const Pose2D& chaser, const Pose2D& port) const;

  /// The APPROACH goal on the safe circle: the point in front of the port, or the nearest circle point
  /// reachable in a straight line (the tangent point) when that one is not.
  Vec2 approachGoal(const Pose2D& chaser, const Pose2D& port) const;

  /// The base_link position when docked: probe tip on the port centre.
  Vec2 dockedPosition(const Pose2D& port) const;

  /// The heading the law asks for: the docked heading, held inside the camera's field of view.
  double desiredHeading(const Pose2D& chaser, const Pose2D& port, bool* fov_limited = nullptr) const;

  /// The proportional command of one phase, with the port's motion fed forward.
  LawCommand command(Phase phase, const Pose2D& chaser, const PortState& port) const;

  /// The remaining plan for display: chaser, approach goal, arc to the port axis, safe point, docked
  /// position (only the parts the current phase still has to do).
  std::vector<Pose2D> plannedPath(Phase phase, const Pose2D& chaser, const Pose2D& port) const;

 private:
  /// One phase's steering in odom: its goal position, the proportional correction, the feed-forward.
  struct Steering {
    Vec2 goal{Vec2::Zero()};
    Vec2 correction{Vec2::Zero()};
    Vec2 feed_forward{Vec2::Zero()};
  };
  Steering steer(Phase phase, const Pose2D& chaser, const PortState& port) const;
  Steering steerApproach(const Pose2D& chaser, const PortState& port) const;
  Steering steerAlign(const Pose2D& chaser, const PortState& port) const;
  Steering steerFinal(const Pose2D& chaser, const PortState& port) const;
  Steering steerBackOff(const Pose2D& chaser, const PortState& port) const;
  Vec2 feedForward(const PortState& port, const Vec2& point) const;
  BodyTwist toBody(const Pose2D& chaser, const Vec2& v_odom, double yaw_rate) const;

  ApproachConfig config_;
  double probe_x_m_;
};

}  // namespace docking_planner
