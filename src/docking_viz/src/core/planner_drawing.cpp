#include "docking_viz/planner_drawing.h"

#include <cmath>
#include <stdexcept>
#include <string>

namespace docking_viz {

namespace {

bool finite(const PlanarPose& pose) { return std::isfinite(pose.x) && std::isfinite(pose.y) && std::isfinite(pose.yaw); }

void requirePositiveFinite(double value, const char* name) {
  if (!std::isfinite(value) || value <= 0.0) {
    throw std::invalid_argument(std::string(name) + " must be positive and finite, got " + std::to_string(value));
  }
}

}  // namespace

void validate(const PlannerRadii& radii) {
  requirePositiveFinite(radii.safe_radius_m, "safe_radius_m");
  requirePositiveFinite(radii.search_orbit_radius_m, "search_orbit_radius_m");
  if (radii.search_orbit_radius_m < radii.safe_radius_m) {
    throw std::invalid_argument("search_orbit_radius_m must not be smaller than safe_radius_m");
  }
}

std::vector<Vec2> circlePolyline(const Vec2& centre, double radius_m, int segments) {
  std::vector<Vec2> points;
  if (!centre.allFinite() || !std::isfinite(radius_m) || radius_m <= 0.0 || segments < kMinCircleSegments) {
    return points;
  }
  points.reserve(static_cast<std::size_t>(segments) + 1);
  for (int i = 0; i < segments; ++i) {
    const double angle = 2.0 * M_PI * i / segments;
    points.push_back(centre + radius_m * Vec2(std::cos(angle), std::sin(angle)));
  }
  points.push_back(points.front());  // closed exactly, not by rounding of cos(2 pi)
  return points;
}

std::optional<PlannerDrawing> drawPlanner(const PlannerView& view, const PlannerRadii& radii, int circle_segments) {
  if (!finite(view.port) || (view.goal && !finite(*view.goal))) return std::nullopt;
  const Vec2 centre(view.port.x, view.port.y);
  PlannerDrawing drawing;
  drawing.safe_circle = circlePolyline(centre, radii.safe_radius_m, circle_segments);
  drawing.search_orbit = circlePolyline(centre, radii.search_orbit_radius_m, circle_segments);
  if (drawing.safe_circle.empty() || drawing.search_orbit.empty()) return std::nullopt;
  if (view.port_orientation_known) {
    // Out to the orbit: the axis then crosses the safe circle at the point where ALIGN ends.
    const Vec2 direction(std::cos(view.port.yaw), std::sin(view.port.yaw));
    drawing.port_axis = LineSegment{centre, centre + radii.search_orbit_radius_m * direction};
  }
  drawing.goal = view.goal;
  return drawing;
}

}  // namespace docking_viz
