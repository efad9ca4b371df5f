// Shared fixtures of the gtests that render with the stress harness (test_mono_stress.cpp,
// test_face_alignment.cpp): the shipped target model, its renderer, the mono_pose parameters from
// config/ and the harness's conditions by name. CONFIG_DIR comes from CMake.
#pragma once

#include <gtest/gtest.h>

#include <string>

#include "docking_perception/mono/mono_pose_estimator.h"
#include "docking_perception/mono/target_model.h"
#include "docking_settings/yaml_loader.h"
#include "mono_stress.h"

namespace docking_perception {
namespace stress_test {

inline const mono::TargetModel& model() {
  static const mono::TargetModel m = mono::TargetModel::loadFromYaml(std::string(CONFIG_DIR) + "/target.yaml");
  return m;
}

inline const stress::StressRenderer& renderer() {
  static const stress::StressRenderer r(model());
  return r;
}

// The shipped configuration of config/mono_pose_<mode>.yaml ("visible" or "ir").
inline mono::MonoPoseParams params(const std::string& mode) {
  return docking_settings::shippedSettings<mono::MonoPoseNodeSettings>(std::string(CONFIG_DIR) + "/mono_pose_" + mode +
                                                                        ".yaml")
      .core;
}

inline stress::StressCondition condition(const std::string& name) {
  for (const stress::StressCondition& c : stress::standardConditions()) {
    if (c.name == name) return c;
  }
  ADD_FAILURE() << "no condition " << name;
  return {};
}

}  // namespace stress_test
}  // namespace docking_perception
