// drawPlanner and circlePolyline: circles at the planner's radii, the axis only with an orientation.
#include <gtest/gtest.h>

#include <cmath>
#include <stdexcept>

#include "docking_viz/planner_drawing.h"

using namespace docking_viz;

namespace {

const PlannerRadii kRadii{0.6, 1.3};  // config/planner.yaml's values at the time of writing

void expectAllAtRadius(const std::vector<Vec2>& points, const Vec2& centre, double radius) {
  ASSERT_FALSE(points.empty());
  for (const Vec2& p : points) EXPECT_NEAR((p - centre).norm(), radius, 1e-12);
}

}  // namespace

TEST(CirclePolyline, AllPointsAtTheRadiusAndClosed) {
  const Vec2 centre(1.5, -2.0);
  const std::vector<Vec2> circle = circlePolyline(centre, 0.6, 72);
  ASSERT_EQ(circle.size(), 73U);
  expectAllAtRadius(circle, centre, 0.6);
  EXPECT_EQ(circle.front(), circle.back());
  // Evenly spaced: every chord the same length.
  const double chord = (circle[1] - circle[0]).norm();
  for (std::size_t i = 1; i < circle.size(); ++i) EXPECT_NEAR((circle[i] - circle[i - 1]).norm(), chord, 1e-12);
}

TEST(CirclePolyline, RefusesUnusableInput) {
  EXPECT_TRUE(circlePolyline(Vec2(0, 0), 0.0, 72).empty());
  EXPECT_TRUE(circlePolyline(Vec2(0, 0), std::nan(""), 72).empty());
  EXPECT_TRUE(circlePolyline(Vec2(std::nan(""), 0), 1.0, 72).empty());
  EXPECT_TRUE(circlePolyline(Vec2(0, 0), 1.0, kMinCircleSegments - 1).empty());
}

TEST(DrawPlanner, CirclesAroundThePortAxisToTheOrbit) {
  PlannerView view;
  view.port = PlanarPose{2.0, 1.0, M_PI / 2.0};
  view.port_orientation_known = true;
  view.goal = PlanarPose{2.0, 1.6, -M_PI / 2.0};
  const auto drawing = drawPlanner(view, kRadii, 64);
  ASSERT_TRUE(drawing);
  const Vec2 centre(2.0, 1.0);
  expectAllAtRadius(drawing->safe_circle, centre, kRadii.safe_radius_m);
  expectAllAtRadius(drawing->search_orbit, centre, kRadii.search_orbit_radius_m);
  ASSERT_TRUE(drawing->port_axis);
  EXPECT_TRUE(drawing->port_axis->from.isApprox(centre));
  EXPECT_NEAR(drawing->port_axis->to.x(), 2.0, 1e-12);  // port axis along +y
  EXPECT_NEAR(drawing->port_axis->to.y(), 1.0 + kRadii.search_orbit_radius_m, 1e-12);
  ASSERT_TRUE(drawing->goal);
  EXPECT_DOUBLE_EQ(drawing->goal->y, 1.6);
}

TEST(DrawPlanner, NoAxisWithoutOrientationAndNothingForNan) {
  PlannerView view;
  view.port = PlanarPose{2.0, 1.0, 0.3};
  view.port_orientation_known = false;  // yaw is the line of sight, not an axis
  const auto drawing = drawPlanner(view, kRadii, 64);
  ASSERT_TRUE(drawing);
  EXPECT_FALSE(drawing->port_axis);
  EXPECT_FALSE(drawing->goal);
  view.port.x = std::nan("");
  EXPECT_FALSE(drawPlanner(view, kRadii, 64));
  view.port.x = 2.0;
  view.goal = PlanarPose{std::nan(""), 0.0, 0.0};
  EXPECT_FALSE(drawPlanner(view, kRadii, 64));
}

TEST(PlannerRadii, ValidationNamesTheParameter) {
  EXPECT_NO_THROW(validate(kRadii));
  try {
    validate(PlannerRadii{-0.6, 1.3});
    FAIL() << "accepted a negative safe radius";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("safe_radius_m"), std::string::npos) << e.what();
  }
  EXPECT_THROW(validate(PlannerRadii{0.6, std::nan("")}), std::invalid_argument);
  EXPECT_THROW(validate(PlannerRadii{0.6, 0.5}), std::invalid_argument);  // orbit inside the circle
}
