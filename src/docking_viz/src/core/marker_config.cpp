#include "docking_viz/marker_config.h"

#include <cmath>
#include <stdexcept>

#include "docking_viz/planner_drawing.h"

namespace docking_viz {

namespace {

void requirePositive(double value, const char* name) {
  if (!std::isfinite(value) || value <= 0.0) {
    throw std::invalid_argument(std::string(name) + " must be positive and finite, got " + std::to_string(value));
  }
}

}  // namespace

void validate(const MarkerConfig& c) {
  requirePositive(c.publish_rate_hz, "publish_rate_hz");
  requirePositive(c.marker_lifetime_s, "marker_lifetime_s");
  requirePositive(c.input_timeout_s, "input_timeout_s");
  requirePositive(c.sigma_scale, "sigma_scale");
  if (c.circle_segments < kMinCircleSegments) {
    throw std::invalid_argument("circle_segments must be at least " + std::to_string(kMinCircleSegments) + ", got " +
                                std::to_string(c.circle_segments));
  }
  requirePositive(c.text_height_m, "text_height_m");
  if (!std::isfinite(c.text_offset_z_m)) throw std::invalid_argument("text_offset_z_m must be finite");
  requirePositive(c.velocity_arrow_s, "velocity_arrow_s");
  requirePositive(c.axis_arrow_length_m, "axis_arrow_length_m");
  if (c.planner_namespace.empty()) throw std::invalid_argument("planner_namespace must not be empty");
}

}  // namespace docking_viz
