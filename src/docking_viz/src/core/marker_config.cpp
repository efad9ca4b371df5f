#include "docking_viz/marker_config.h"

#include <stdexcept>

#include "docking_viz/planner_drawing.h"

namespace docking_viz {

void validate(const MarkerConfig& c) {
  docking_settings::validateSettings(c);
  static_assert(kMinCircleSegments == 8, "settings/markers.yaml: circle_segments' range starts at kMinCircleSegments");
  if (c.planner_namespace.empty()) throw std::invalid_argument("planner_namespace must not be empty");
}

}  // namespace docking_viz
