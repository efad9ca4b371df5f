// The port from the mockup's footprint (footprint_fit.h): on depth profiles ray-cast from the mockup's
// top-down outline, and through the detector on a disparity image of a turned mockup, where the
// nearest layer's centroid lies beside the port.
#include <cmath>
#include <random>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include "docking_perception/disparity/disparity_detector.h"
#include "docking_perception/disparity/footprint_fit.h"
#include "painted_disparity.h"
#include "synthetic_stereo.h"

namespace docking_perception {
namespace disparity {
namespace {

constexpr double kPi = 3.14159265358979323846;
const std::string kConfigDir = DISPARITY_CONFIG_DIR;

StereoGeometry geometry640() { return test::ourGeometry(); }

// One part of the mockup seen from above, with the rows it covers (half its height) and whether block
// matching finds texture on it (the box walls are plain).
struct Part {
  Eigen::Vector2d a, b;
  double half_height_m;
  bool textured;
};

// The mockup's outline with the port at `port` (X, Z) and the face normal `yaw` from the line of sight
// to the camera (positive towards +X), as footprint_fit.h defines it.
std::vector<Part> mockupParts(const TargetShape& s, const Eigen::Vector2d& port, double yaw) {
  const Eigen::Vector2d to_camera = (-port).normalized();
  const Eigen::Vector2d n(std::cos(yaw) * to_camera.x() - std::sin(yaw) * to_camera.y(),
                          std::sin(yaw) * to_camera.x() + std::cos(yaw) * to_camera.y());
  const Eigen::Vector2d along(-n.y(), n.x());
  auto at = [&](double behind, double aside) { return Eigen::Vector2d(port - behind * n + aside * along); };
  const double w = 0.5 * s.face_width_m, d = s.body_depth_m, p = s.panel_offset_behind_face_m;
  const double h = 0.5 * s.face_height_m, ph = 0.5 * s.panel_height_m;
  return {{at(0, -w), at(0, w), h, true},         {at(d, -w), at(d, w), h, false},
          {at(0, w), at(d, w), h, false},         {at(0, -w), at(d, -w), h, false},
          {at(p, w), at(p, w + s.panel_span_m), ph, true},
          {at(p, -w), at(p, -w - s.panel_span_m), ph, true}};
}

// Depth along the ray of column u (X/Z = t) to the nearest part, and that part; -1 when it misses.
int castColumn(const std::vector<Part>& parts, double t, double* depth) {
  int hit = -1;
  *depth = 1e9;
  for (std::size_t i = 0; i < parts.size(); ++i) {
    // Ray (t z, z) meets a + s (b - a): solve for s in [0, 1].
    const Eigen::Vector2d a = parts[i].a, ab = parts[i].b - parts[i].a;
    const double denominator = ab.x() - t * ab.y();
    if (std::abs(denominator) < 1e-12) continue;
    const double s = (t * a.y() - a.x()) / denominator;
    if (s < 0.0 || s > 1.0) continue;
    const double z = a.y() + s * ab.y();
    if (z > 0.0 && z < *depth) {
      *depth = z;
      hit = static_cast<int>(i);
    }
  }
  return hit;
}

// The disparity image of the turned mockup, level with the cameras (port on the optical axis' height):
// textured parts only, with a column-wise noise of `noise_px` (seeded).
cv::Mat renderMockupDisparity(const TargetShape& shape, const Eigen::Vector2d& port, double yaw,
                              double noise_px, unsigned seed) {
  const StereoGeometry g = geometry640();
  cv::Mat disparity(480, 640, CV_32F, cv::Scalar(0.0f));
  const auto parts = mockupParts(shape, port, yaw);
  std::mt19937 random(seed);
  std::normal_distribution<double> noise(0.0, noise_px);
  for (int u = 0; u < disparity.cols; ++u) {
    double z = 0.0;
    const int hit = castColumn(parts, (u - g.cx_px) / g.focal_px, &z);
    if (hit < 0 || !parts[static_cast<std::size_t>(hit)].textured) continue;
    const double half_px = parts[static_cast<std::size_t>(hit)].half_height_m * g.focal_px / z;
    for (int v = static_cast<int>(std::ceil(g.cy_px - half_px)); v <= static_cast<int>(g.cy_px + half_px); ++v) {
      disparity.at<float>(v, u) = static_cast<float>(g.focal_px * g.baseline_m / z + noise(random));
    }
  }
  return disparity;
}

// The profile the detector would build from that image.
std::vector<Eigen::Vector2d> profileOf(const cv::Mat& disparity) {
  std::vector<int> columns;
  std::vector<float> values;
  for (int v = 0; v < disparity.rows; ++v) {
    for (int u = 0; u < disparity.cols; ++u) {
      if (disparity.at<float>(v, u) > 0.0f) {
        columns.push_back(u);
        values.push_back(disparity.at<float>(v, u));
      }
    }
  }
  return columnProfile(columns, values, geometry640());
}

struct TurnedCase {
  double range_m, bearing_deg, yaw_deg;
};

Eigen::Vector2d portAt(const TurnedCase& c) {
  const double bearing = c.bearing_deg * kPi / 180.0;
  return Eigen::Vector2d(c.range_m * std::sin(bearing), c.range_m * std::cos(bearing));
}

class FootprintFitOnTurnedMockup : public ::testing::TestWithParam<TurnedCase> {};

TEST_P(FootprintFitOnTurnedMockup, FindsThePortAndTheYaw) {
  const TurnedCase c = GetParam();
  const TargetShape shape = loadTargetShape(kConfigDir + "/target.yaml");
  const Eigen::Vector2d port = portAt(c);
  const auto profile = profileOf(renderMockupDisparity(shape, port, c.yaw_deg * kPi / 180.0, 0.05, 3));
  const FootprintFit fit = fitFootprint(profile, shape, geometry640(), FootprintFitParams());
  ASSERT_TRUE(fit.valid);
  EXPECT_LT((fit.port_xz - port).norm(), 0.02 * c.range_m)
      << "fitted port (" << fit.port_xz.transpose() << ") vs (" << port.transpose() << ")";
  EXPECT_NEAR(fit.yaw_rad * 180.0 / kPi, c.yaw_deg, 6.0);
  EXPECT_GT(fit.inlier_fraction, 0.9);
}

INSTANTIATE_TEST_SUITE_P(FaceOnToFiftyFiveDegrees, FootprintFitOnTurnedMockup,
                         ::testing::Values(TurnedCase{3.0, 0.0, 0.0}, TurnedCase{4.0, -8.0, 30.0},
                                           TurnedCase{4.0, 6.0, -30.0}, TurnedCase{4.0, -5.0, 55.0},
                                           TurnedCase{2.5, 10.0, -55.0}, TurnedCase{5.5, 3.0, 45.0}));

TEST(FootprintFit, TooFewColumnsIsNoFit) {
  const std::vector<Eigen::Vector2d> profile{{0.0, 4.0}, {0.01, 4.0}, {0.02, 4.0}};
  EXPECT_FALSE(fitFootprint(profile, TargetShape(), geometry640(), FootprintFitParams()).valid);
}

TEST(FootprintFit, AWallIsMostlyOffTheOutline) {
  // A 3 m strip of wall, turned 6 degrees: the mockup's 1.2 m outline covers less than half of it.
  std::vector<Eigen::Vector2d> profile;
  for (double s = -1.5; s <= 1.5; s += 0.02) profile.emplace_back(s * std::cos(0.1), 4.0 + s * std::sin(0.1));
  const FootprintFit fit = fitFootprint(profile, TargetShape(), geometry640(), FootprintFitParams());
  ASSERT_TRUE(fit.valid);
  EXPECT_LT(fit.inlier_fraction, 0.5);
}

TEST(FootprintFit, ColumnProfileTakesEachColumnsMedianAndSkipsSparseColumns) {
  const StereoGeometry g = geometry640();
  // Column 330: three pixels at 11, 11 and 30 px (an outlier); column 331: two pixels only.
  const auto profile = columnProfile({330, 330, 330, 331, 331}, {11.0f, 30.0f, 11.0f, 11.0f, 11.0f}, g, 3);
  ASSERT_EQ(profile.size(), 1u);
  EXPECT_NEAR(profile[0].y(), 5.0, 1e-9);  // 550 * 0.1 / 11
  EXPECT_NEAR(profile[0].x(), (330 - 319.5) * 5.0 / 550.0, 1e-9);
}

TEST(FootprintFit, TargetShapeReadsThePanelsOffset) {
  const TargetShape shape = loadTargetShape(kConfigDir + "/target.yaml");
  EXPECT_NEAR(shape.panel_offset_behind_face_m, 0.15, 1e-9);
}

// Through the detector, with config/disparity_detector.yaml: a mockup turned 50 degrees at 4 m, whose
// nearest layer is its near panel and the face's near edge. Their centroid is more than 5 cm from the
// port here (0.1-0.4 m in rendered scenes, where more of the panel is matched); the footprint's port is
// within 2 % of the range.
TEST(FootprintFit, TheDetectorReportsThePortOfATurnedMockup) {
  DetectorParams params = testing::shippedDetectorSettings(kConfigDir).detector;
  const TargetShape shape = loadTargetShape(kConfigDir + "/target.yaml");
  const TurnedCase c{4.0, -4.0, 50.0};
  const Eigen::Vector2d port = portAt(c);
  const cv::Mat disparity = renderMockupDisparity(shape, port, c.yaw_deg * kPi / 180.0, 0.05, 5);
  const Eigen::Vector3d truth(port.x(), 0.0, port.y());

  const RigGeometry rig = testing::shippedRig(kConfigDir);
  const Detection fitted = DisparityDetector(params, shape, rig).detect(disparity, geometry640(), 0.0, 96.0);
  ASSERT_TRUE(fitted.found) << fitted.reason;
  EXPECT_TRUE(fitted.footprint_fitted);
  EXPECT_LT((fitted.position_m - truth).norm(), 0.02 * c.range_m) << fitted.position_m.transpose();

  params.footprint_fit_enabled = false;  // the nearest layer's centroid instead, for comparison
  const Detection nearest = DisparityDetector(params, shape, rig).detect(disparity, geometry640(), 0.0, 96.0);
  ASSERT_TRUE(nearest.found) << nearest.reason;
  EXPECT_FALSE(nearest.footprint_fitted);
  EXPECT_GT((nearest.position_m - truth).norm(), 0.05) << nearest.position_m.transpose();
}

}  // namespace
}  // namespace disparity
}  // namespace docking_perception
