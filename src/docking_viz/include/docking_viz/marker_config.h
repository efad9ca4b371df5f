// The markers node's settings (declared in settings/markers.yaml, generated MarkerConfig), validated
// before the node starts. ROS-free.
#pragma once

#include "docking_viz/marker_settings.h"

namespace docking_viz {

/// The declaration's ranges, and what they cannot say; throws std::invalid_argument naming the setting.
void validate(const MarkerConfig& config);

}  // namespace docking_viz
