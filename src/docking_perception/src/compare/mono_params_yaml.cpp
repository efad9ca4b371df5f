#include "mono_params_yaml.h"

#include <yaml-cpp/yaml.h>

#include <vector>

namespace docking_perception {
namespace compare {
namespace {

template <typename T>
bool read(const YAML::Node& root, const std::string& key, T* value, std::string* error) {
  const YAML::Node node = root[key];
  if (!node) {
    *error = "missing parameter '" + key + "'";
    return false;
  }
  try {
    *value = node.as<T>();
  } catch (const YAML::Exception&) {
    *error = "mistyped parameter '" + key + "'";
    return false;
  }
  return true;
}

}  // namespace

bool loadMonoParams(const std::string& yaml_path, mono::MonoPoseParams* params, std::string* error) {
  YAML::Node root;
  try {
    root = YAML::LoadFile(yaml_path);
  } catch (const YAML::Exception& e) {
    *error = yaml_path + ": " + e.what();
    return false;
  }
  mono::MonoPoseParams p;
  std::string mode, solver, velocity;
  std::string e;
  const bool ok =
      read(root, "mode", &mode, &e) && read(root, "solver", &solver, &e) &&
      read(root, "velocity_method", &velocity, &e) && read(root, "use_tracking_region", &p.use_tracking_region, &e) &&
      read(root, "tracking_margin_px", &p.tracking_margin_px, &e) &&
      read(root, "max_reprojection_px", &p.max_reprojection_px, &e) &&
      read(root, "min_pixel_sigma", &p.min_pixel_sigma, &e) && read(root, "min_range_m", &p.min_range_m, &e) &&
      read(root, "max_range_m", &p.max_range_m, &e) &&
      read(root, "max_pattern_candidates", &p.max_pattern_candidates, &e) &&
      read(root, "use_brisk_detector", &p.features.use_brisk_detector, &e) &&
      read(root, "fast_threshold", &p.features.fast_threshold, &e) &&
      read(root, "brisk_threshold", &p.features.brisk_threshold, &e) &&
      read(root, "brisk_octaves", &p.features.brisk_octaves, &e) &&
      read(root, "max_image_keypoints", &p.features.max_image_keypoints, &e) &&
      read(root, "max_model_keypoints_per_level", &p.features.max_model_keypoints_per_level, &e) &&
      read(root, "model_widths_px", &p.features.model_widths_px, &e) &&
      read(root, "feature_ratio", &p.features.ratio, &e) &&
      read(root, "ransac_threshold_px", &p.features.ransac_threshold_px, &e) &&
      read(root, "min_inliers", &p.features.min_inliers, &e) &&
      read(root, "min_face_area_px", &p.features.min_face_area_px, &e) &&
      read(root, "refine_matches", &p.features.refine, &e) &&
      read(root, "min_correlation", &p.features.min_correlation, &e) &&
      read(root, "max_refined_points", &p.features.max_refined_points, &e) &&
      read(root, "led_threshold", &p.leds.threshold, &e) && read(root, "led_min_area_px", &p.leds.min_area_px, &e) &&
      read(root, "led_max_area_px", &p.leds.max_area_px, &e) &&
      read(root, "led_min_fill_ratio", &p.leds.min_fill_ratio, &e) &&
      read(root, "led_max_aspect_ratio", &p.leds.max_aspect_ratio, &e) &&
      read(root, "led_max_blobs", &p.leds.max_blobs, &e) &&
      read(root, "led_collinearity_tolerance", &p.leds.collinearity_tolerance, &e) &&
      read(root, "led_midpoint_tolerance", &p.leds.midpoint_tolerance, &e) &&
      read(root, "dot_search_radius_factor", &p.dots.search_radius_factor, &e) &&
      read(root, "dot_min_contrast", &p.dots.min_contrast, &e) &&
      read(root, "pnp_ambiguity_ratio", &p.pnp.ambiguity_ratio, &e) &&
      read(root, "pnp_ambiguity_floor_px", &p.pnp.ambiguity_floor_px, &e) &&
      read(root, "accel_noise", &p.filter.accel_noise, &e) &&
      read(root, "angular_accel_noise", &p.filter.angular_accel_noise, &e) &&
      read(root, "max_gap_s", &p.filter.max_gap_s, &e) && read(root, "gate_chi2", &p.filter.gate_chi2, &e) &&
      read(root, "max_rejections", &p.filter.max_rejections, &e);
  if (!ok) {
    *error = yaml_path + ": " + e;
    return false;
  }
  if (!mono::parseMonoMode(mode, &p.mode) || !mono::parsePoseSolver(solver, &p.solver) ||
      !mono::parseVelocityMethod(velocity, &p.velocity)) {
    *error = yaml_path + ": unknown mode, solver or velocity_method";
    return false;
  }
  p.pnp.min_pixel_sigma = p.min_pixel_sigma;
  const std::string invalid = mono::validateParams(p);
  if (!invalid.empty()) {
    *error = yaml_path + ": " + invalid;
    return false;
  }
  *params = p;
  return true;
}

}  // namespace compare
}  // namespace docking_perception
