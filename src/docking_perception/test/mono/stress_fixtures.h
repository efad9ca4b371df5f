// Shared fixtures of the gtests that render with the stress harness (test_mono_stress.cpp,
// test_face_alignment.cpp): the shipped target model, its renderer, the mono_pose parameters from
// config/ and the harness's conditions by name. CONFIG_DIR comes from CMake.
#pragma once

#include <gtest/gtest.h>

#include <string>

#include "docking_perception/mono/mono_pose_estimator.h"
#include "docking_perception/mono/target_model.h"
#include "mono_params_yaml.h"
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

// config/mono_pose_<mode>.yaml ("visible" or "ir").
inline mono::MonoPoseParams params(const std::string& mode) {
  mono::MonoPoseParams p;
  std::string error;
  EXPECT_TRUE(compare::loadMonoParams(std::string(CONFIG_DIR) + "/mono_pose_" + mode + ".yaml", &p, &error)) << error;
  return p;
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
