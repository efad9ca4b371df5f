#include "docking_sim/simulation.h"

#include <algorithm>
#include <atomic>
#include <cmath>
#include <exception>
#include <thread>
#include <vector>

#include "docking_sim/config_error.h"

namespace docking_sim {
namespace {

const LightingScenario& pickLighting(const SimSettings& settings, const Scenario& scenario) {
  const auto it = settings.lighting.find(scenario.lighting);
  if (it == settings.lighting.end()) {
    std::string known;
    for (const auto& kv : settings.lighting) known += (known.empty() ? "" : ", ") + kv.first;
    throw ConfigError(scenario.file, "scenario.lighting",
                      "unknown lighting '" + scenario.lighting + "' (" + settings.file + " defines: " + known + ")");
  }
  return it->second;
}

Scenario validated(Scenario scenario, const SimSettings& settings, const RobotModel& robot) {
  const RoomConfig& room = settings.room;
  auto inside = [&](const omni_base::Pose2D& p, double margin) {
    return p.x > room.x_min_m + margin && p.x < room.x_max_m - margin && p.y > room.y_min_m + margin &&
           p.y < room.y_max_m - margin;
  };
  const double target_radius = 0.25;  // the mockup's box half-diagonal, roughly
  if (!inside(scenario.chaser_start, robot.footprint_radius_m)) {
    throw ConfigError(scenario.file, "scenario.chaser", "start pose is outside the room of " + settings.file);
  }
  if (!inside(scenario.target_start, target_radius)) {
    throw ConfigError(scenario.file, "scenario.target", "start pose is outside the room of " + settings.file);
  }
  const double gap = std::hypot(scenario.chaser_start.x - scenario.target_start.x,
                                scenario.chaser_start.y - scenario.target_start.y);
  if (gap < robot.footprint_radius_m + target_radius) {
    throw ConfigError(scenario.file, "scenario.target", "start pose overlaps the chaser");
  }
  return scenario;
}

Eigen::Isometry3d planarPose(double x, double y, double yaw) {
  Eigen::Isometry3d t = Eigen::Isometry3d::Identity();
  t.translation() = Eigen::Vector3d(x, y, 0.0);
  t.linear() = Eigen::AngleAxisd(yaw, Eigen::Vector3d::UnitZ()).toRotationMatrix();
  return t;
}

/// sim.yaml as this scenario sees it: extra clutter, its light direction, its camera overrides.
SimSettings scenarioSettings(SimSettings settings, const Scenario& scenario) {
  for (const auto& box : scenario.extra_clutter) settings.room.clutter.push_back(box);
  if (scenario.has_light_direction) settings.light_direction = scenario.light_direction;
  applyCameraOverrides(scenario, Band::kVisible, &settings.visible_effects);
  applyCameraOverrides(scenario, Band::kInfrared, &settings.ir_effects);
  return settings;
}

}  // namespace

Simulation::Simulation(const SimulationFiles& files, const RenderOptions& render_options)
    : scenario_(loadScenario(files.scenario)),
      settings_(scenarioSettings(loadSimSettings(files.sim_config), scenario_)),
      target_(loadTargetModel(files.target_config)),
      robot_(loadRobotModel(files.robot_config)),
      base_model_(loadOmniBaseModel(files.omni_base_config)),
      lighting_(pickLighting(settings_, scenario_)),
      chaser_(base_model_, settings_.command_timeout_s, scenario_.chaser_start),
      kinematics_(base_model_.layout),
      scene_(settings_, target_, lighting_, scenario_.seed) {
  scenario_ = validated(scenario_, settings_, robot_);
  camera_scenes_.fill(scene_);
  for (int i = 0; i < 3; ++i) {
    const CameraMount& cam = robot_.cameras[static_cast<std::size_t>(i)];
    const CameraEffects& effects = cam.band == Band::kVisible ? settings_.visible_effects : settings_.ir_effects;
    renderers_[static_cast<std::size_t>(i)] = std::make_unique<CameraRenderer>(
        cam.calibration, cam.band, effects, lighting_, scenario_.seed * 3 + static_cast<uint64_t>(i), render_options);
  }
  // Auto-exposure settles on its first frame (up to 10 renders): do it here, before time runs, so the
  // node's first frames do not fall behind real time and arrive in a burst.
  for (int i = 0; i < 3; ++i) {
    if (renderers_[static_cast<std::size_t>(i)]->effects().ae_enabled && render_options.effects) render(i);
  }
}

void Simulation::advance(double dt_s) {
  if (!(dt_s > 0.0)) return;
  if (scenario_.chaser_motion.scripted()) {
    omni_base::Twist2D twist;
    twist.wz = scenario_.chaser_motion.yawRateAt(time_s_);
    chaser_.command(true, kinematics_.inverse(twist), time_s_);
  }
  chaser_.step(time_s_, dt_s);
  time_s_ += dt_s;
}

Eigen::Isometry3d Simulation::worldTChaser() const {
  const auto& p = chaser_.pose();
  return planarPose(p.x, p.y, p.yaw);
}

Eigen::Isometry3d Simulation::worldTTargetRobotAt(double t_s) const {
  const auto& s = scenario_.target_start;
  const auto& m = scenario_.target_motion;
  const Eigen::Isometry3d on_floor =
      planarPose(s.x + m.velocity_x_m_s * t_s, s.y + m.velocity_y_m_s * t_s, s.yaw + m.yaw_rate_rad_s * t_s);
  if (scenario_.target_roll_rad == 0.0) return on_floor;
  // Rolled about the port's own axis (its x, out of the face): the port stays where it was, the face and
  // everything on it turn in the chaser's images.
  const Eigen::Isometry3d& robot_T_port = target_.robot_T_port;
  Eigen::Isometry3d roll = Eigen::Isometry3d::Identity();
  roll.linear() = Eigen::AngleAxisd(scenario_.target_roll_rad, Eigen::Vector3d::UnitX()).toRotationMatrix();
  return on_floor * robot_T_port * roll * robot_T_port.inverse();
}

Eigen::Isometry3d Simulation::worldTCameraAt(int camera, double dt_s) const {
  const omni_base::Pose2D p = integrateTwist(chaser_.pose(), chaser_.twist(), dt_s);
  return planarPose(p.x, p.y, p.yaw) * baseTCamera(camera);
}

Eigen::Isometry3d Simulation::baseTCamera(int camera) const {
  const Eigen::Isometry3d& mount = robot_.cameras.at(static_cast<std::size_t>(camera)).base_T_camera;
  if (scenario_.camera_tilt_roll_rad == 0.0 && scenario_.camera_tilt_pitch_rad == 0.0) return mount;
  // The head turns rigidly about the reference camera's centre (camera 0), so the stereo pair keeps its
  // calibration and only its pose on the robot is off.
  const Eigen::Vector3d pivot = robot_.cameras.front().base_T_camera.translation();
  Eigen::Isometry3d tilt = Eigen::Isometry3d::Identity();
  tilt.linear() = (Eigen::AngleAxisd(scenario_.camera_tilt_roll_rad, Eigen::Vector3d::UnitX()) *
                   Eigen::AngleAxisd(scenario_.camera_tilt_pitch_rad, Eigen::Vector3d::UnitY()))
                      .toRotationMatrix();
  tilt.translation() = pivot - tilt.linear() * pivot;
  return tilt * mount;
}

Eigen::Isometry3d Simulation::worldTPort() const { return worldTTargetRobot() * target_.robot_T_port; }

Eigen::Isometry3d Simulation::worldTCamera(int camera) const { return worldTChaser() * baseTCamera(camera); }

void Simulation::chaserVelocityWorld(Eigen::Vector3d* linear, Eigen::Vector3d* angular) const {
  const auto twist = chaser_.twist();
  const double yaw = chaser_.pose().yaw;
  *linear = Eigen::Vector3d(std::cos(yaw) * twist.vx - std::sin(yaw) * twist.vy,
                            std::sin(yaw) * twist.vx + std::cos(yaw) * twist.vy, 0.0);
  *angular = Eigen::Vector3d(0.0, 0.0, twist.wz);
}

RelativeTruth Simulation::truthInCamera(int camera) const {
  const Eigen::Isometry3d world_T_camera = worldTCamera(camera);
  const Eigen::Isometry3d world_T_port = worldTPort();
  const Eigen::Isometry3d world_T_target = worldTTargetRobot();
  RelativeTruth truth;
  truth.camera_T_port = world_T_camera.inverse() * world_T_port;

  // Velocities in world: the port rides on the rotating, translating target robot; the camera rides
  // on the chaser.
  const Eigen::Vector3d target_w(0, 0, scenario_.target_motion.yaw_rate_rad_s);
  const Eigen::Vector3d target_v(scenario_.target_motion.velocity_x_m_s, scenario_.target_motion.velocity_y_m_s, 0);
  const Eigen::Vector3d port_v =
      target_v + target_w.cross(world_T_port.translation() - world_T_target.translation());
  Eigen::Vector3d chaser_v, chaser_w;
  chaserVelocityWorld(&chaser_v, &chaser_w);
  const Eigen::Vector3d camera_v =
      chaser_v + chaser_w.cross(world_T_camera.translation() - worldTChaser().translation());
  const Eigen::Matrix3d camera_R_world = world_T_camera.linear().transpose();
  const Eigen::Vector3d offset = world_T_port.translation() - world_T_camera.translation();
  // d/dt [R_cw (p - c)] = R_cw [(v_p - v_c) - w_c x (p - c)]
  truth.linear_m_s = camera_R_world * ((port_v - camera_v) - chaser_w.cross(offset));
  truth.angular_rad_s = camera_R_world * (target_w - chaser_w);
  return truth;
}

void Simulation::updateSharedScene() {
  if (scene_time_s_ != time_s_) {
    scene_.update(worldTTargetRobot());
    scene_time_s_ = time_s_;
  }
}

const cv::Mat& Simulation::renderOwnScene(int camera) {
  ExposureMotion motion;
  motion.world_T_camera = [this, camera](double dt) { return worldTCameraAt(camera, dt); };
  motion.world_T_target_robot = [this](double dt) { return worldTTargetRobotAt(time_s_ + dt); };
  const auto index = static_cast<std::size_t>(camera);
  return renderers_.at(index)->render(camera_scenes_.at(index), motion);
}

const cv::Mat& Simulation::render(int camera) {
  updateSharedScene();
  return renderOwnScene(camera);
}

std::array<const cv::Mat*, 3> Simulation::renderCameras(const std::array<bool, 3>& wanted, int threads) {
  updateSharedScene();
  std::array<const cv::Mat*, 3> frames{{nullptr, nullptr, nullptr}};
  std::vector<int> jobs;
  for (int i = 0; i < 3; ++i) {
    if (wanted[static_cast<std::size_t>(i)]) jobs.push_back(i);
  }
  // Workers take the next camera in order until none is left; the caller's thread is one of them.
  std::atomic<std::size_t> next{0};
  std::array<std::exception_ptr, 3> errors;
  auto work = [&]() {
    for (std::size_t j = next++; j < jobs.size(); j = next++) {
      const auto camera = static_cast<std::size_t>(jobs[j]);
      try {
        frames[camera] = &renderOwnScene(jobs[j]);
      } catch (...) {
        errors[camera] = std::current_exception();
      }
    }
  };
  const int helpers = std::clamp(threads, 1, std::max<int>(1, static_cast<int>(jobs.size()))) - 1;
  std::vector<std::thread> pool;
  for (int t = 0; t < helpers; ++t) pool.emplace_back(work);
  work();
  for (auto& thread : pool) thread.join();
  for (const auto& error : errors) {
    if (error) std::rethrow_exception(error);
  }
  return frames;
}

}  // namespace docking_sim
