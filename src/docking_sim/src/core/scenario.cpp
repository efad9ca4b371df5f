#include "docking_sim/scenario.h"

#include <cmath>

#include "yaml_field.h"

namespace docking_sim {
namespace {

constexpr double kDegToRad = M_PI / 180.0;

omni_base::Pose2D readPose(const YamlField& f) {
  omni_base::Pose2D p;
  p.x = f["x_m"].asDouble(-1000.0, 1000.0);
  p.y = f["y_m"].asDouble(-1000.0, 1000.0);
  p.yaw = f["yaw_deg"].asDouble(-360.0, 360.0) * kDegToRad;
  return p;
}

std::string baseName(const std::string& path) {
  const auto slash = path.find_last_of('/');
  std::string name = (slash == std::string::npos) ? path : path.substr(slash + 1);
  const auto dot = name.rfind(".yaml");
  return dot == std::string::npos ? name : name.substr(0, dot);
}

}  // namespace

double ChaserMotionSpec::yawRateAt(double t_s) const {
  if (!(reverse_every_s > 0.0)) return yaw_rate_rad_s;
  // Segments: [0, T/2) +, [T/2, 3T/2) -, [3T/2, 5T/2) +, ...
  const long segment = static_cast<long>(std::floor((t_s + 0.5 * reverse_every_s) / reverse_every_s));
  return segment % 2 == 0 ? yaw_rate_rad_s : -yaw_rate_rad_s;
}

void applyCameraOverrides(const Scenario& scenario, Band band, CameraEffects* effects) {
  if (!scenario.has_camera_overrides) return;
  const YamlField overrides = YamlField::open(scenario.file)["scenario"]["camera_overrides"];
  const std::string key = band == Band::kVisible ? "visible" : "ir";
  if (overrides.has(key)) readCameraEffects(overrides[key], true, band == Band::kInfrared, effects);
}

Scenario loadScenario(const std::string& path) {
  const YamlField root = YamlField::open(path);
  const YamlField s = root["scenario"];
  Scenario out;
  out.file = path;
  out.name = baseName(path);
  if (s.has("description")) out.description = s["description"].asString();
  out.duration_s = s["duration_s"].asDouble(0.0, 1e6);
  out.seed = static_cast<uint64_t>(s["seed"].asInteger(0, 1LL << 62));
  out.lighting = s["lighting"].asString();
  out.chaser_start = readPose(s["chaser"]);
  out.target_start = readPose(s["target"]);
  if (s["target"].has("roll_deg")) out.target_roll_rad = s["target"]["roll_deg"].asDouble(-180.0, 180.0) * kDegToRad;
  if (s["target"].has("motion")) {
    const YamlField m = s["target"]["motion"];
    out.target_motion.yaw_rate_rad_s = m["yaw_rate_deg_s"].asDouble(-360.0, 360.0) * kDegToRad;
    const auto v = m["velocity_m_s"].asVector(2);
    if (std::hypot(v[0], v[1]) > 2.0) m["velocity_m_s"].fail("faster than 2 m/s: not a test-bed motion");
    out.target_motion.velocity_x_m_s = v[0];
    out.target_motion.velocity_y_m_s = v[1];
  }
  if (s["chaser"].has("camera_tilt")) {
    const YamlField tilt = s["chaser"]["camera_tilt"];
    out.camera_tilt_roll_rad = tilt["roll_deg"].asDouble(-180.0, 180.0) * kDegToRad;
    out.camera_tilt_pitch_rad = tilt["pitch_deg"].asDouble(-30.0, 30.0) * kDegToRad;
  }
  if (s["chaser"].has("motion")) {
    const YamlField m = s["chaser"]["motion"];
    out.chaser_motion.yaw_rate_rad_s = m["yaw_rate_deg_s"].asDouble(-180.0, 180.0) * kDegToRad;
    out.chaser_motion.reverse_every_s = m["reverse_every_s"].asDouble(0.0, 1e6);
  }
  if (s.has("extra_clutter")) {
    const YamlField clutter = s["extra_clutter"];
    for (std::size_t i = 0; i < clutter.size(); ++i) out.extra_clutter.push_back(readClutterBox(clutter.at(i)));
  }
  if (s.has("light_direction")) {
    const auto d = s["light_direction"].asVector(3);
    out.light_direction = Eigen::Vector3d(d[0], d[1], d[2]);
    if (out.light_direction.norm() < 1e-6) s["light_direction"].fail("must not be the zero vector");
    out.light_direction.normalize();
    out.has_light_direction = true;
  }
  if (s.has("camera_overrides")) {
    // Validated here (every key known, in range), applied by the simulation on sim.yaml's values.
    const YamlField o = s["camera_overrides"];
    if (!o.isMap()) o.fail("must be a map {visible: {...}, ir: {...}}");
    for (const auto& band : o.keys()) {
      if (band != "visible" && band != "ir") o[band].fail("unknown camera band '" + band + "' (visible, ir)");
      CameraEffects check;
      readCameraEffects(o[band], true, band == "ir", &check);
    }
    out.has_camera_overrides = true;
  }
  return out;
}

}  // namespace docking_sim
