// The whole simulated test bed without ROS: the chaser base, the scripted target, the scene and the
// three camera renderers, advanced in sim time. The node wraps this; tools and tests use it directly.
#pragma once

#include <Eigen/Geometry>
#include <opencv2/core.hpp>

#include <array>
#include <memory>
#include <string>

#include "docking_sim/chaser_base.h"
#include "docking_sim/configs.h"
#include "docking_sim/renderer.h"
#include "docking_sim/scenario.h"
#include "docking_sim/scene.h"

namespace docking_sim {

struct SimulationFiles {
  std::string sim_config;        ///< config/sim.yaml
  std::string scenario;          ///< config/scenarios/<name>.yaml
  std::string target_config;     ///< config/target.yaml
  std::string robot_config;      ///< config/robot.yaml
  std::string omni_base_config;  ///< config/omni_base.yaml
};

/// Pose and velocity of the target's docking port relative to a camera, in the camera's optical frame.
struct RelativeTruth {
  Eigen::Isometry3d camera_T_port{Eigen::Isometry3d::Identity()};
  Eigen::Vector3d linear_m_s{Eigen::Vector3d::Zero()};    ///< d/dt of the port origin in camera coordinates
  Eigen::Vector3d angular_rad_s{Eigen::Vector3d::Zero()}; ///< target minus camera angular velocity, camera axes
};

class Simulation {
 public:
  /// Loads and validates every file; throws ConfigError naming the file and field.
  explicit Simulation(const SimulationFiles& files, const RenderOptions& render_options = {});

  double time() const { return time_s_; }
  /// Advances the physics by dt_s (any positive step; the motors and poses integrate exactly).
  void advance(double dt_s);

  /// A wheel command now. Ignored (kIgnoredScripted) while the scenario scripts the chaser's motion.
  CommandResult wheelCommand(bool enable, const std::vector<double>& wheel_rad_s) {
    if (scenario_.chaser_motion.scripted()) return CommandResult::kIgnoredScripted;
    return chaser_.command(enable, wheel_rad_s, time_s_);
  }
  const ChaserBase& chaser() const { return chaser_; }
  /// Puts the chaser at `pose` (world, base_link on the floor) without moving it there: for tools that
  /// render a path of their own (sim_render --approach).
  void placeChaser(const omni_base::Pose2D& pose) { chaser_.place(pose); }

  Eigen::Isometry3d worldTChaser() const;          ///< base_link, on the floor
  Eigen::Isometry3d worldTTargetRobot() const { return worldTTargetRobotAt(time_s_); }
  /// The scripted target robot at any sim time (closed form).
  Eigen::Isometry3d worldTTargetRobotAt(double t_s) const;
  /// A camera's pose dt_s from now: the chaser moved by its current body twist (exact arc), as over an
  /// exposure (tens of ms, against the motors' 20 ms lag: the twist barely changes).
  Eigen::Isometry3d worldTCameraAt(int camera, double dt_s) const;
  /// The camera on the chaser: its robot.yaml mount, turned with the head by scenario.chaser.camera_tilt.
  Eigen::Isometry3d baseTCamera(int camera) const;
  Eigen::Isometry3d worldTPort() const;            ///< target_truth
  Eigen::Isometry3d worldTCamera(int camera) const;
  /// Chaser velocity in world: linear (m/s) of base_link's origin and angular (rad/s).
  void chaserVelocityWorld(Eigen::Vector3d* linear, Eigen::Vector3d* angular) const;
  RelativeTruth truthInCamera(int camera) const;

  /// Renders camera RobotModel::kStereoLeft / kStereoRight / kIr for an exposure centred on the current
  /// time (the stamp): motion blur from both robots' motion across it.
  const cv::Mat& render(int camera);
  /// Renders the cameras whose entry in `wanted` is true, on up to `threads` threads (the caller's
  /// thread among them), and returns each one's frame (null where not wanted). Each camera renders its
  /// own copy of the scene with its own noise generator, so the frames are the same whatever the
  /// thread count or the order in which the threads finish.
  std::array<const cv::Mat*, 3> renderCameras(const std::array<bool, 3>& wanted, int threads);
  const CameraRenderer& renderer(int camera) const { return *renderers_.at(static_cast<std::size_t>(camera)); }

  const SimSettings& settings() const { return settings_; }
  const Scenario& scenario() const { return scenario_; }
  const TargetModel& target() const { return target_; }
  const RobotModel& robot() const { return robot_; }
  const LightingScenario& lighting() const { return lighting_; }
  const Scene& scene() const { return scene_; }

 private:
  Scenario scenario_;       // (before settings_: the settings take its overrides)
  SimSettings settings_;    ///< sim.yaml with the scenario's overrides applied
  TargetModel target_;
  RobotModel robot_;
  OmniBaseModel base_model_;
  LightingScenario lighting_;
  ChaserBase chaser_;
  omni_base::OmniKinematics kinematics_;  ///< for the scripted chaser motion's wheel commands
  Scene scene_;
  /// One scene per camera: rendering moves the target across the exposure (motion blur) in the scene
  /// it draws, so cameras rendered at once cannot share one.
  std::array<Scene, 3> camera_scenes_;
  std::array<std::unique_ptr<CameraRenderer>, 3> renderers_;
  double time_s_{0.0};
  double scene_time_s_{-1.0};

  /// The scene at the current time (scene()), outside the per-camera copies.
  void updateSharedScene();
  /// Renders one camera into its renderer from its own scene copy; touches nothing shared.
  const cv::Mat& renderOwnScene(int camera);
};

}  // namespace docking_sim
