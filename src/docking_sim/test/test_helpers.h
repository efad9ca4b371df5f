// Shared helpers for the docking_sim gtests: temporary scenario files next to the real config.
#pragma once

#include <cstdio>
#include <fstream>
#include <string>

#include <unistd.h>

#include "docking_sim/simulation.h"

namespace docking_sim_test {

inline std::string configDir() { return SIM_CONFIG_DIR; }

/// Writes text to a fresh file under /tmp and returns its path.
inline std::string writeTempFile(const std::string& stem, const std::string& text) {
  const std::string path = "/tmp/docking_sim_test_" + std::to_string(getpid()) + "_" + stem + ".yaml";
  std::ofstream(path) << text;
  return path;
}

inline std::string scenarioText(double target_x, double target_y, double target_yaw_deg, double yaw_rate_deg_s = 0.0,
                                const std::string& lighting = "nominal") {
  return "scenario:\n  duration_s: 10\n  seed: 1\n  lighting: " + lighting +
         "\n  chaser: {x_m: 0.0, y_m: 0.0, yaw_deg: 0.0}\n  target:\n    x_m: " + std::to_string(target_x) +
         "\n    y_m: " + std::to_string(target_y) + "\n    yaw_deg: " + std::to_string(target_yaw_deg) +
         "\n    motion: {yaw_rate_deg_s: " + std::to_string(yaw_rate_deg_s) + ", velocity_m_s: [0.0, 0.0]}\n";
}

inline docking_sim::SimulationFiles files(const std::string& scenario_path) {
  docking_sim::SimulationFiles f;
  f.sim_config = configDir() + "/sim.yaml";
  f.scenario = scenario_path;
  f.target_config = configDir() + "/target.yaml";
  f.robot_config = configDir() + "/robot.yaml";
  f.omni_base_config = configDir() + "/omni_base.yaml";
  return f;
}

}  // namespace docking_sim_test
