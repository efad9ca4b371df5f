// The one list of the numeric and boolean MonoPoseParams fields and their parameter names (the keys of
// config/mono_pose_<mode>.yaml). The mono_pose nodelet reads them from the ROS parameter server and
// offline tools from the YAML file through this list, so a new parameter cannot be read by one and
// forgotten by the other. `mode`, `solver` and `velocity_method` are strings and parsed separately.
#pragma once

#include <cmath>
#include <string>

#include "docking_perception/duty/fused_range_condition.h"
#include "docking_perception/mono/mono_pose_estimator.h"

namespace docking_perception {
namespace mono {

// Calls visit(key, &field) for every field; field types are bool, int, double and std::vector<int>.
template <typename Visitor>
void visitMonoPoseParams(MonoPoseParams& p, Visitor&& visit) {
  visit("use_tracking_region", &p.use_tracking_region);
  visit("tracking_margin_px", &p.tracking_margin_px);
  visit("max_reprojection_px", &p.max_reprojection_px);
  visit("min_pixel_sigma", &p.min_pixel_sigma);
  visit("min_range_m", &p.min_range_m);
  visit("max_range_m", &p.max_range_m);
  visit("max_pattern_candidates", &p.max_pattern_candidates);
  visit("use_brisk_detector", &p.features.use_brisk_detector);
  visit("upright_descriptors", &p.features.upright_descriptors);
  visit("fast_threshold", &p.features.fast_threshold);
  visit("brisk_threshold", &p.features.brisk_threshold);
  visit("brisk_octaves", &p.features.brisk_octaves);
  visit("max_image_keypoints", &p.features.max_image_keypoints);
  visit("max_model_keypoints_per_level", &p.features.max_model_keypoints_per_level);
  visit("model_widths_px", &p.features.model_widths_px);
  visit("feature_ratio", &p.features.ratio);
  visit("ransac_threshold_px", &p.features.ransac_threshold_px);
  visit("min_inliers", &p.features.min_inliers);
  visit("min_face_area_px", &p.features.min_face_area_px);
  visit("refine_matches", &p.features.refine);
  visit("min_correlation", &p.features.min_correlation);
  visit("max_refined_points", &p.features.max_refined_points);
  visit("refine_passes", &p.features.refine_passes);
  visit("refine_again_move_px", &p.features.refine_again_move_px);
  visit("led_threshold", &p.leds.threshold);
  visit("led_min_area_px", &p.leds.min_area_px);
  visit("led_max_area_px", &p.leds.max_area_px);
  visit("led_min_fill_ratio", &p.leds.min_fill_ratio);
  visit("led_max_aspect_ratio", &p.leds.max_aspect_ratio);
  visit("led_max_blobs", &p.leds.max_blobs);
  visit("led_min_contrast", &p.leds.min_contrast);
  visit("led_collinearity_tolerance", &p.leds.collinearity_tolerance);
  visit("led_midpoint_tolerance", &p.leds.midpoint_tolerance);
  visit("dot_search_radius_factor", &p.dots.search_radius_factor);
  visit("dot_min_contrast", &p.dots.min_contrast);
  visit("pnp_ambiguity_ratio", &p.pnp.ambiguity_ratio);
  visit("pnp_ambiguity_floor_px", &p.pnp.ambiguity_floor_px);
  visit("publish_filtered_orientation", &p.publish_filtered_orientation);
  visit("filtered_orientation_correlated_fraction", &p.filtered_orientation_correlated_fraction);
  visit("accel_noise", &p.filter.accel_noise);
  visit("angular_accel_noise", &p.filter.angular_accel_noise);
  visit("max_gap_s", &p.filter.max_gap_s);
  visit("gate_chi2", &p.filter.gate_chi2);
  visit("max_rejections", &p.filter.max_rejections);
  visit("inner_pattern_enabled", &p.inner_pattern.enabled);
  visit("inner_pattern_use_range_m", &p.inner_pattern.use_range_m);
  visit("inner_pattern_quad_decimate", &p.inner_pattern.quad_decimate);
  visit("inner_pattern_max_reprojection_px", &p.inner_pattern.max_reprojection_px);
  visit("inner_pattern_min_pixel_sigma", &p.inner_pattern.min_pixel_sigma);
  visit("inner_pattern_min_decision_margin", &p.inner_pattern.min_decision_margin);
  visit("inner_pattern_min_tag_edge_px", &p.inner_pattern.min_tag_edge_px);
  visit("inner_pattern_min_points", &p.inner_pattern.min_points);
  visit("inner_pattern_cross_check_position_m", &p.inner_pattern.cross_check_position_m);
  visit("inner_pattern_cross_check_angle_rad", &p.inner_pattern.cross_check_angle_rad);
  visit("inner_pattern_face_retry_every", &p.inner_pattern.face_retry_every);
  // Issue 11: search under blur and clutter, consistency checks and the covariance model.
  visit("use_half_resolution", &p.use_half_resolution);
  // Issue 15: tracking without the feature search.
  visit("predict_face_when_tracking", &p.predict_face_when_tracking);
  visit("predicted_face_min_kept_fraction", &p.predicted_face_min_kept_fraction);
  visit("keypoint_grid", &p.features.keypoint_grid);
  visit("blurred_model_sigma_px", &p.features.blurred_model_sigma_px);
  visit("blur_matched_refinement", &p.features.blur_matched_refinement);
  visit("refinement_row_smears_px", &p.features.refinement_row_smears_px);
  visit("search_row_smear_px", &p.features.search_row_smear_px);
  visit("region_hint_max_age_s", &p.region_hint_max_age_s);
  visit("region_hint_radius_m", &p.region_hint_radius_m);
  visit("min_inlier_spread", &p.consistency.min_inlier_spread);
  visit("min_appearance_ncc", &p.consistency.min_appearance_ncc);
  visit("max_ambiguity_deg", &p.consistency.max_ambiguity_deg);
  visit("ambiguity_chi2", &p.consistency.ambiguity_chi2);
  visit("covariance_blur_gain", &p.consistency.blur_gain);
  visit("position_floor_fraction", &p.consistency.position_floor_fraction);
  visit("rotation_floor_deg", &p.consistency.rotation_floor_deg);
  visit("max_rotation_sigma_deg", &p.consistency.max_rotation_sigma_deg);
  visit("max_position_sigma_fraction", &p.consistency.max_position_sigma_fraction);
  visit("position_sigma_check_max_range_m", &p.consistency.position_sigma_check_max_range_m);
  visit("innovation_window_frames", &p.consistency.innovation_window_frames);
  visit("max_rotation_innovation_chi2", &p.consistency.max_rotation_innovation_chi2);
  visit("confirm_new_orientation", &p.consistency.confirm_new_orientation);
  visit("max_hint_disagreement_fraction", &p.consistency.max_hint_disagreement_fraction);
  visit("hint_check_min_range_m", &p.consistency.hint_check_min_range_m);
  visit("hint_disagreement_hold_s", &p.consistency.hint_disagreement_hold_s);
  visit("hint_recovery_fraction", &p.consistency.hint_recovery_fraction);
  visit("max_dot_offset_factor", &p.consistency.max_dot_offset_factor);
  visit("max_solver_disagreement_deg", &p.consistency.max_solver_disagreement_deg);
  visit("max_led_area_ratio", &p.consistency.max_led_area_ratio);
  visit("max_led_elongation", &p.consistency.max_led_elongation);
  visit("led_still_streak_px", &p.consistency.led_still_streak_px);
  visit("face_scale_bias_px", &p.consistency.face_scale_bias_px);
  visit("smear_shape_bias_fraction", &p.consistency.smear_shape_bias_fraction);
  visit("motion_smear_exposure_s", &p.consistency.motion_smear_exposure_s);
  visit("direct_smear_shape_bias_fraction", &p.consistency.direct_smear_shape_bias_fraction);
  // Issue 11: direct (ECC) alignment of the face when the features fail (face_alignment.h).
  visit("use_direct_alignment", &p.use_direct_alignment);
  visit("direct_yaw_hypotheses", &p.direct_yaw_hypotheses);
  visit("direct_max_yaw_deg", &p.direct_max_yaw_deg);
  visit("direct_min_correlation", &p.direct.min_correlation);
  visit("direct_working_face_width_px", &p.direct.working_face_width_px);
  visit("direct_pyramid_levels", &p.direct.pyramid_levels);
  visit("direct_max_iterations", &p.direct.max_iterations);
  visit("direct_grid_columns", &p.direct.grid_columns);
  visit("direct_grid_rows", &p.direct.grid_rows);
}

// The far throttle (issue 15): settings the mono_pose nodelet reads itself, beside MonoPoseParams (same
// YAML files). Far on disparity (`far`, a duty::FusedRangeCondition beyond its range), images are
// processed at most max_rate_hz.
struct FarThrottleSettings {
  duty::FusedRangeConditionParams far;  // range_m 0: off
  double max_rate_hz = 0.0;             // 0: no limit
};

template <typename Visitor>
void visitFarThrottleSettings(FarThrottleSettings& s, Visitor&& visit) {
  visit("far_throttle_beyond_range_m", &s.far.range_m);
  visit("far_throttle_hysteresis_m", &s.far.hysteresis_m);
  visit("far_throttle_max_fused_age_s", &s.far.max_fused_age_s);
  visit("far_throttle_max_rate_hz", &s.max_rate_hz);
}

// The first problem with the settings ("<key> must be ..."), or empty.
inline std::string validateFarThrottle(const FarThrottleSettings& s) {
  const auto off_or_positive = [](double v) { return std::isfinite(v) && v >= 0.0; };
  if (!off_or_positive(s.far.range_m)) return "far_throttle_beyond_range_m must be a number >= 0 (0: off)";
  if (!off_or_positive(s.far.hysteresis_m)) return "far_throttle_hysteresis_m must be a number >= 0";
  if (!(std::isfinite(s.far.max_fused_age_s) && s.far.max_fused_age_s > 0.0)) {
    return "far_throttle_max_fused_age_s must be > 0";
  }
  if (!off_or_positive(s.max_rate_hz)) return "far_throttle_max_rate_hz must be a number >= 0 (0: no limit)";
  return "";
}

}  // namespace mono
}  // namespace docking_perception
