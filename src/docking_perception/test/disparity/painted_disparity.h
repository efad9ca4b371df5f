// Synthetic disparity images for the detector's gtests: our stereo pair's geometry and fronto-parallel
// rectangles painted at a depth, and the shipped configuration the tests run (shared by
// test_disparity_detector.cpp, test_target_confirmation.cpp and test_face_appearance.cpp).
#pragma once

#include <cmath>
#include <string>

#include <docking_settings/yaml_loader.h>
#include <opencv2/core.hpp>

#include "docking_perception/disparity/disparity_detector.h"
#include "synthetic_stereo.h"

namespace docking_perception {
namespace disparity {
namespace test {

// Our pair: 640x480, f = 550 px, principal point at the image centre, baseline 0.10 m.
inline StereoGeometry ourGeometry() {
  StereoGeometry g;
  g.focal_px = 550.0;
  g.cx_px = 319.5;
  g.cy_px = 239.5;
  g.baseline_m = 0.10;
  return g;
}

// The detector node's settings as shipped: the declared defaults with config/disparity_detector.yaml's values
// (DISPARITY_CONFIG_DIR: the workspace's config/). A test that changes one says which and why.
inline DisparityDetectorSettings shippedSettings() {
  return docking_settings::shippedSettings<DisparityDetectorSettings>(std::string(DISPARITY_CONFIG_DIR) +
                                                                      "/disparity_detector.yaml");
}
inline DetectorParams shippedParams() { return shippedSettings().detector; }
// The mockup of config/target.yaml (the node's ~target_yaml).
inline TargetShape shippedShape() { return loadTargetShape(std::string(DISPARITY_CONFIG_DIR) + "/target.yaml"); }
// The rig of config/robot.yaml, config/target.yaml and config/stereo_image_proc.yaml (the node's).
inline RigGeometry shippedRig() { return testing::shippedRig(DISPARITY_CONFIG_DIR); }
inline DisparityDetector detectorWith(const DetectorParams& params) {
  return DisparityDetector(params, shippedShape(), shippedRig());
}
inline DisparityDetector shippedDetector() { return detectorWith(shippedParams()); }

inline double disparityAt(double z_m) { return ourGeometry().focal_px * ourGeometry().baseline_m / z_m; }

// Paints the image rectangle of a fronto-parallel rectangle (centre x, y, depth z, size w x h, metres);
// a later rectangle overwrites an earlier one, so paint far to near.
inline void paintRect(cv::Mat* disparity, double x, double y, double z, double w, double h) {
  const StereoGeometry g = ourGeometry();
  const int u0 = static_cast<int>(std::lround(g.cx_px + (x - w / 2) * g.focal_px / z));
  const int u1 = static_cast<int>(std::lround(g.cx_px + (x + w / 2) * g.focal_px / z));
  const int v0 = static_cast<int>(std::lround(g.cy_px + (y - h / 2) * g.focal_px / z));
  const int v1 = static_cast<int>(std::lround(g.cy_px + (y + h / 2) * g.focal_px / z));
  const cv::Rect rect = cv::Rect(cv::Point(u0, v0), cv::Point(u1 + 1, v1 + 1)) &
                        cv::Rect(0, 0, disparity->cols, disparity->rows);
  (*disparity)(rect).setTo(cv::Scalar(disparityAt(z)));
}

}  // namespace test
}  // namespace disparity
}  // namespace docking_perception
