// The markers node's parameters (config/markers.yaml), validated before the node starts. ROS-free.
#pragma once

#include <string>

namespace docking_viz {

struct MarkerConfig {
  double publish_rate_hz{10.0};     ///< marker array rate while someone subscribes
  double marker_lifetime_s{1.0};    ///< rviz drops a marker not refreshed for this long (a dead node's view clears)
  double input_timeout_s{1.0};      ///< an input received longer ago than this is no longer drawn
  double sigma_scale{3.0};          ///< covariance ellipsoids: semi-axes in standard deviations
  int circle_segments{72};          ///< chords per circle
  double text_height_m{0.06};       ///< height of a capital letter of the state label
  double text_offset_z_m{0.6};      ///< the label this far above base_link
  double velocity_arrow_s{2.0};     ///< commanded velocity arrow: length (m) per m/s
  double axis_arrow_length_m{0.25};  ///< an estimate's port axis arrow
  std::string planner_namespace{"planner"};  ///< where the planner's parameters are (safe_radius_m, ...)
};

/// Throws std::invalid_argument naming the bad parameter.
void validate(const MarkerConfig& config);

}  // namespace docking_viz
