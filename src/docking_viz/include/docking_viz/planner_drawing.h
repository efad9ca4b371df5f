// The planner's geometry as shapes in its plane (the odom frame: x, y in m, yaw in rad), for display.
// ROS-free. The radii are the planner's own parameters (safe_radius_m, search_orbit_radius_m), read by
// the node from the planner's namespace; the port and the goal are what the planner reports
// (docking_msgs/PlannerGeometry).
#pragma once

#include <Eigen/Core>
#include <optional>
#include <vector>

namespace docking_viz {

using Vec2 = Eigen::Vector2d;

/// Fewer segments than this do not look like a circle.
constexpr int kMinCircleSegments = 8;

struct PlanarPose {
  double x{0.0};
  double y{0.0};
  double yaw{0.0};
};

/// The planner's radii, as named in config/planner.yaml.
struct PlannerRadii {
  double safe_radius_m{0.0};
  double search_orbit_radius_m{0.0};
};
/// Throws std::invalid_argument naming the bad parameter: both positive and finite, the orbit not
/// inside the safe circle (the planner's own rule).
void validate(const PlannerRadii& radii);

/// What the planner holds this cycle.
struct PlannerView {
  PlanarPose port;                    ///< port centre; yaw = port axis, out of the face
  bool port_orientation_known{false};  ///< false: yaw means nothing to draw (position only)
  std::optional<PlanarPose> goal;     ///< the current phase's goal
};

struct LineSegment {
  Vec2 from{Vec2::Zero()};
  Vec2 to{Vec2::Zero()};
};

struct PlannerDrawing {
  std::vector<Vec2> safe_circle;      ///< closed polyline (last point = first) around the port
  std::vector<Vec2> search_orbit;     ///< closed polyline around the port
  std::optional<LineSegment> port_axis;  ///< from the port centre out to the search orbit; absent without orientation
  std::optional<PlanarPose> goal;
};

/// A closed polyline of `segments` chords (segments + 1 points) on the circle. Empty for a non-finite
/// centre or radius, a radius <= 0, or fewer than kMinCircleSegments segments.
std::vector<Vec2> circlePolyline(const Vec2& centre, double radius_m, int segments);

/// The shapes of `view`; nullopt when a number of it is not finite (nothing half-drawn).
std::optional<PlannerDrawing> drawPlanner(const PlannerView& view, const PlannerRadii& radii, int circle_segments);

}  // namespace docking_viz
