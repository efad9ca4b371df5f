// The shipped configuration for the core tests: the declared defaults with config/planner.yaml's values
// (docking_settings::shippedSettings), and the probe tip from config/robot.yaml (robot data). A test that
// changes a setting says which and why.
#pragma once

#include <docking_settings/yaml_loader.h>

#include "docking_planner/docking_planner.h"

namespace docking_planner {

inline PlannerConfig shippedConfig() {
  return docking_settings::shippedSettings<PlannerNodeSettings>(PLANNER_CONFIG_DIR "/planner.yaml").core;
}

/// config/robot.yaml's chaser.docking_probe_x_m.
inline double shippedProbeX() {
  const std::string path = PLANNER_CONFIG_DIR "/robot.yaml";
  return docking_settings::convertYaml<double>(docking_settings::readYamlKeys(path).at("chaser/docking_probe_x_m"),
                                               path);
}

}  // namespace docking_planner
