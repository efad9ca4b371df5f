#include "docking_planner/safe_circle_approach.h"

#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <string>

namespace docking_planner {

const char* phaseName(Phase phase) {
  switch (phase) {
    case Phase::kApproach:
      return "approach";
    case Phase::kAlign:
      return "align";
    case Phase::kFinal:
      return "final";
    case Phase::kBackOff:
      return "back_off";
  }
  return "unknown";
}

void validate(const ApproachConfig& c) {
  docking_settings::validateSettings(c);
  if (c.fov_margin_rad >= c.camera_half_fov_rad || c.camera_half_fov_rad >= M_PI / 2) {
    throw std::invalid_argument("fov_margin_rad must be below camera_half_fov_rad, itself below pi/2");
  }
}

SafeCircleApproach::SafeCircleApproach(const ApproachConfig& config, double probe_x_m)
    : config_(config), probe_x_m_(probe_x_m) {
  validate(config_);
  if (!std::isfinite(probe_x_m_) || probe_x_m_ < 0.0 || probe_x_m_ >= config_.safe_radius_m) {
    throw std::invalid_argument("probe_x_m must be in [0, safe_radius_m)");
  }
}

ApproachGeometry SafeCircleApproach::measure(const Pose2D& chaser, const Pose2D& port) const {
  ApproachGeometry g;
  const Vec2 rel = chaser.position() - port.position();  // port -> chaser
  const Vec2 axis = unitAt(port.yaw);
  g.range_m = rel.norm();
  g.polar_angle_rad = wrapAngle(std::atan2(rel.y(), rel.x()) - port.yaw);
  g.axial_m = rel.dot(axis);
  g.lateral_m = rel.dot(perpendicular(axis));
  g.yaw_error_rad = wrapAngle(chaser.yaw - (port.yaw + M_PI));
  g.bearing_rad = wrapAngle(std::atan2(-rel.y(), -rel.x()) - chaser.yaw);
  g.tip_error_m = (chaser.position() + probe_x_m_ * unitAt(chaser.yaw) - port.position()).norm();
  return g;
}

Vec2 SafeCircleApproach::approachGoal(const Pose2D& chaser, const Pose2D& port) const {
  const double r_safe = config_.safe_radius_m;
  const Vec2 rel = chaser.position() - port.position();
  const double r = rel.norm();
  const double gamma = wrapAngle(std::atan2(rel.y(), rel.x()) - port.yaw);
  double goal_gamma = gamma;  // inside the circle: straight out to it
  if (r > r_safe) {
    // A straight segment to the circle point at polar angle g stays outside the circle while
    // |g - gamma| <= acos(R / r) (the tangent points); move the goal towards the axis by at most that.
    const double reach = std::max(0.0, std::acos(r_safe / r) - kTangentMarginRad);
    goal_gamma = gamma - clampAbs(gamma, reach);
  }
  return port.position() + r_safe * unitAt(port.yaw + goal_gamma);
}

Vec2 SafeCircleApproach::dockedPosition(const Pose2D& port) const {
  return port.position() + probe_x_m_ * unitAt(port.yaw);
}

double SafeCircleApproach::desiredHeading(const Pose2D& chaser, const Pose2D& port, bool* fov_limited) const {
  const double docked_heading = wrapAngle(port.yaw + M_PI);
  const Vec2 to_port = port.position() - chaser.position();
  bool limited = false;
  double heading = docked_heading;
  if (to_port.norm() > 1e-6) {
    const double line_of_sight = std::atan2(to_port.y(), to_port.x());
    const double limit = config_.camera_half_fov_rad - config_.fov_margin_rad;
    const double bearing = wrapAngle(line_of_sight - docked_heading);  // bearing if we took the docked heading
    if (std::abs(bearing) > limit) {
      heading = wrapAngle(line_of_sight - clampAbs(bearing, limit));
      limited = true;
    }
  }
  if (fov_limited) *fov_limited = limited;
  return heading;
}

Vec2 SafeCircleApproach::feedForward(const PortState& port, const Vec2& point) const {
  // Velocity of a point rigidly attached to the port's frame.
  return port.velocity + port.yaw_rate * perpendicular(point - port.pose.position());
}

BodyTwist SafeCircleApproach::toBody(const Pose2D& chaser, const Vec2& v_odom, double yaw_rate) const {
  const Vec2 v = clampNorm(v_odom, config_.max_speed_mps);
  const double c = std::cos(chaser.yaw), s = std::sin(chaser.yaw);
  BodyTwist t;
  t.vx = c * v.x() + s * v.y();
  t.vy = -s * v.x() + c * v.y();
  t.wz = clampAbs(yaw_rate, config_.max_yaw_rate_radps);
  return t;
}

namespace {
// The unit vector port centre -> chaser (the port axis when the chaser is on the centre).
Vec2 radialOf(const Vec2& rel, double r, const Pose2D& port) { return r > 1e-9 ? Vec2(rel / r) : unitAt(port.yaw); }
}  // namespace

SafeCircleApproach::Steering SafeCircleApproach::steerApproach(const Pose2D& chaser, const PortState& port) const {
  Steering s;
  s.goal = approachGoal(chaser, port.pose);
  s.correction = clampNorm(config_.travel_gain * (s.goal - chaser.position()), config_.max_speed_mps);
  s.feed_forward = feedForward(port, s.goal);  // far away the goal, not the chaser, moves with the port
  return s;
}

// Along the arc towards gamma = 0 (paper: v ~ SafeDistance * theta), holding the radius.
SafeCircleApproach::Steering SafeCircleApproach::steerAlign(const Pose2D& chaser, const PortState& port) const {
  const ApproachConfig& c = config_;
  const Pose2D& p = port.pose;
  const Vec2 rel = chaser.position() - p.position();
  const double r = rel.norm();
  const Vec2 radial = radialOf(rel, r, p);
  const double gamma = wrapAngle(std::atan2(radial.y(), radial.x()) - p.yaw);
  const Vec2 tangent = perpendicular(radial);  // direction of increasing gamma
  const double v_t = clampAbs(-c.travel_gain * c.safe_radius_m * gamma, c.align_speed_mps);
  const double v_r = clampAbs(c.correction_gain * (c.safe_radius_m - r), c.align_speed_mps);
  Steering s;
  s.correction = v_t * tangent + v_r * radial;
  s.goal = p.position() + c.safe_radius_m * unitAt(p.yaw);
  s.feed_forward = feedForward(port, chaser.position());
  return s;
}

// Along the port axis to contact; the lateral and heading errors are closed before advancing: full
// axial speed only when both are small.
SafeCircleApproach::Steering SafeCircleApproach::steerFinal(const Pose2D& chaser, const PortState& port) const {
  const ApproachConfig& c = config_;
  const Pose2D& p = port.pose;
  const Vec2 rel = chaser.position() - p.position();
  const Vec2 axis = unitAt(p.yaw);
  const Vec2 left = perpendicular(axis);
  const double axial_to_contact = rel.dot(axis) - probe_x_m_;  // > 0: not there yet
  const double lateral = rel.dot(left);
  const double yaw_error = wrapAngle(chaser.yaw - (p.yaw + M_PI));
  const double gate = std::clamp(
      1.0 - std::max(std::abs(lateral) / c.final_lateral_gate_m, std::abs(yaw_error) / c.final_yaw_gate_rad), 0.0, 1.0);
  const double tip_distance = std::max(axial_to_contact, 0.0);
  const double speed_limit =
      tip_distance < c.final_slow_distance_m ? kSlowZoneSpeedFraction * c.final_speed_mps : c.final_speed_mps;
  double v_axial = clampAbs(-c.correction_gain * axial_to_contact, speed_limit);
  if (v_axial < 0.0) v_axial *= gate;  // advancing is gated; backing out of an overshoot is not
  const double v_lateral = clampAbs(-c.correction_gain * lateral, c.final_speed_mps);
  Steering s;
  s.correction = v_axial * axis + v_lateral * left;
  s.goal = dockedPosition(p);
  s.feed_forward = feedForward(port, chaser.position());
  return s;
}

// Radially out to the safe circle; nothing once outside it.
SafeCircleApproach::Steering SafeCircleApproach::steerBackOff(const Pose2D& chaser, const PortState& port) const {
  const Pose2D& p = port.pose;
  const Vec2 pc = chaser.position();
  const Vec2 rel = pc - p.position();
  const double r = rel.norm();
  Steering s;
  s.goal = p.position() + config_.safe_radius_m * radialOf(rel, r, p);
  s.correction = r < config_.safe_radius_m ? clampNorm(config_.correction_gain * (s.goal - pc), config_.align_speed_mps)
                                           : Vec2::Zero();
  s.feed_forward = feedForward(port, pc);
  return s;
}

SafeCircleApproach::Steering SafeCircleApproach::steer(Phase phase, const Pose2D& chaser, const PortState& port) const {
  switch (phase) {
    case Phase::kApproach:
      return steerApproach(chaser, port);
    case Phase::kAlign:
      return steerAlign(chaser, port);
    case Phase::kFinal:
      return steerFinal(chaser, port);
    case Phase::kBackOff:
      break;
  }
  return steerBackOff(chaser, port);
}

// The phase's steering, the heading, the port's motion fed forward, the limits.
LawCommand SafeCircleApproach::command(Phase phase, const Pose2D& chaser, const PortState& port) const {
  const Pose2D& p = port.pose;
  const Steering steering = steer(phase, chaser, port);
  LawCommand out;
  out.goal.x = steering.goal.x();
  out.goal.y = steering.goal.y();
  // FINAL keeps the docked heading exactly (the port is too close and too wide to matter for the
  // field of view; contact needs the heading); the other phases keep the port in view.
  const double heading =
      phase == Phase::kFinal ? wrapAngle(p.yaw + M_PI) : desiredHeading(chaser, p, &out.fov_limited);
  out.goal.yaw = heading;
  const double yaw_rate = port.yaw_rate + config_.correction_gain * wrapAngle(heading - chaser.yaw);
  out.velocity_odom = clampNorm(steering.correction + steering.feed_forward, config_.max_speed_mps);
  out.twist = toBody(chaser, out.velocity_odom, yaw_rate);
  out.goal_distance_m = (out.goal.position() - chaser.position()).norm();
  return out;
}

std::vector<Pose2D> SafeCircleApproach::plannedPath(Phase phase, const Pose2D& chaser, const Pose2D& port) const {
  const double r_safe = config_.safe_radius_m;
  const double docked_heading = wrapAngle(port.yaw + M_PI);
  std::vector<Pose2D> path;
  path.push_back(chaser);
  auto add = [&](const Vec2& v, double yaw) { path.push_back(Pose2D{v.x(), v.y(), yaw}); };
  auto addArc = [&](double from_gamma) {
    // Points every ~5 degrees from `from_gamma` to the port axis, facing the port.
    const int steps = std::max(1, static_cast<int>(std::ceil(std::abs(from_gamma) / 0.087)));
    for (int i = 0; i <= steps; ++i) {
      const double g = from_gamma * (1.0 - static_cast<double>(i) / steps);
      add(port.position() + r_safe * unitAt(port.yaw + g), wrapAngle(port.yaw + g + M_PI));
    }
  };
  const Vec2 rel = chaser.position() - port.position();
  switch (phase) {
    case Phase::kApproach: {
      const Vec2 goal = approachGoal(chaser, port);
      const Vec2 g_rel = goal - port.position();
      addArc(wrapAngle(std::atan2(g_rel.y(), g_rel.x()) - port.yaw));
      add(dockedPosition(port), docked_heading);
      break;
    }
    case Phase::kAlign:
      addArc(wrapAngle(std::atan2(rel.y(), rel.x()) - port.yaw));
      add(dockedPosition(port), docked_heading);
      break;
    case Phase::kFinal:
      add(dockedPosition(port), docked_heading);
      break;
    case Phase::kBackOff: {
      const double n = rel.norm();
      const Vec2 radial = n > 1e-9 ? Vec2(rel / n) : unitAt(port.yaw);
      add(port.position() + r_safe * radial, chaser.yaw);
      break;
    }
  }
  return path;
}

}  // namespace docking_planner
