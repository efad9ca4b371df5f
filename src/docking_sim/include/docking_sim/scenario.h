// Scenario files (config/scenarios/*.yaml): start poses, target motion, lighting, seed, duration.
#pragma once

#include <Eigen/Core>

#include <cstdint>
#include <string>
#include <vector>

#include "docking_sim/configs.h"
#include "omni_base/kinematics.h"

namespace docking_sim {

struct TargetMotionSpec {
  double yaw_rate_rad_s{0.0};     ///< constant rotation about the target robot's vertical axis
  double velocity_x_m_s{0.0};     ///< constant translation in world
  double velocity_y_m_s{0.0};
};

/// A scripted turn of the chaser (perception scenarios: motion blur of a turning robot). The simulator
/// commands the base itself (wheel commands from outside are ignored), so odometry, encoders and
/// truth agree: yaw rate +rate for the first reverse_every_s / 2, then alternating sign every
/// reverse_every_s (the heading sweeps +-rate * reverse_every_s / 2 around the start; 0: never reverses).
struct ChaserMotionSpec {
  double yaw_rate_rad_s{0.0};
  double reverse_every_s{0.0};
  bool scripted() const { return yaw_rate_rad_s != 0.0; }
  /// The commanded yaw rate at sim time t_s.
  double yawRateAt(double t_s) const;
};

struct Scenario {
  std::string name;
  std::string description;
  double duration_s{0.0};         ///< 0: run until stopped
  uint64_t seed{1};
  std::string lighting;           ///< a key of sim.yaml `lighting`
  omni_base::Pose2D chaser_start;
  omni_base::Pose2D target_start;
  /// scenario.target.roll_deg: the target turned about its port's axis (a print glued at an angle, a ramp, a
  /// target not kept upright as in orbit); drawn and in the truth. 0: upright, as on the level floor.
  double target_roll_rad{0.0};
  /// scenario.chaser.camera_tilt {roll_deg, pitch_deg}: the camera head (every camera, rigidly) turned about
  /// the reference camera's centre, roll about the robot's forward axis and pitch about its left axis, unknown
  /// to the stack (robot.yaml keeps the nominal mounts): a camera mounted with a tilt. Drawn and in the truth.
  double camera_tilt_roll_rad{0.0};
  double camera_tilt_pitch_rad{0.0};
  TargetMotionSpec target_motion;
  ChaserMotionSpec chaser_motion;          ///< scenario.chaser.motion (optional)
  std::vector<ClutterBox> extra_clutter;   ///< scenario.extra_clutter: boxes added to sim.yaml's room
  bool has_light_direction{false};         ///< scenario.light_direction overrides shading.light_direction
  Eigen::Vector3d light_direction{0, 0, -1};
  bool has_camera_overrides{false};        ///< scenario.camera_overrides {visible: {...}, ir: {...}}
  std::string file;
};

/// Applies the scenario's camera_overrides for one band (keys as in sim.yaml cameras.<band>) onto
/// `effects`. Throws ConfigError naming the scenario file and the field.
void applyCameraOverrides(const Scenario& scenario, Band band, CameraEffects* effects);

/// Reads and validates one scenario file; throws ConfigError naming the file and the field.
Scenario loadScenario(const std::string& path);

}  // namespace docking_sim
