// Scenario files (config/scenarios/*.yaml): start poses, target motion, lighting, seed, duration.
#pragma once

#include <cstdint>
#include <string>

#include "omni_base/kinematics.h"

namespace docking_sim {

struct TargetMotionSpec {
  double yaw_rate_rad_s{0.0};     ///< constant rotation about the target robot's vertical axis
  double velocity_x_m_s{0.0};     ///< constant translation in world
  double velocity_y_m_s{0.0};
};

struct Scenario {
  std::string name;
  std::string description;
  double duration_s{0.0};         ///< 0: run until stopped
  uint64_t seed{1};
  std::string lighting;           ///< a key of sim.yaml `lighting`
  omni_base::Pose2D chaser_start;
  omni_base::Pose2D target_start;
  TargetMotionSpec target_motion;
  std::string file;
};

/// Reads and validates one scenario file; throws ConfigError naming the file and the field.
Scenario loadScenario(const std::string& path);

}  // namespace docking_sim
