// MonoPoseParams from config/mono_pose_<mode>.yaml without ROS: the keys the mono_pose node reads
// (every one required, as there), for offline tools. ROS-free.
#pragma once

#include <string>

#include "docking_perception/mono/mono_pose_estimator.h"

namespace docking_perception {
namespace compare {

// Fills *params; false with the reason (the first missing or invalid key) otherwise.
bool loadMonoParams(const std::string& yaml_path, mono::MonoPoseParams* params, std::string* error);

}  // namespace compare
}  // namespace docking_perception
