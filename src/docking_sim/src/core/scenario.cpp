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
  if (s["target"].has("motion")) {
    const YamlField m = s["target"]["motion"];
    out.target_motion.yaw_rate_rad_s = m["yaw_rate_deg_s"].asDouble(-360.0, 360.0) * kDegToRad;
    const auto v = m["velocity_m_s"].asVector(2);
    if (std::hypot(v[0], v[1]) > 2.0) m["velocity_m_s"].fail("faster than 2 m/s: not a test-bed motion");
    out.target_motion.velocity_x_m_s = v[0];
    out.target_motion.velocity_y_m_s = v[1];
  }
  return out;
}

}  // namespace docking_sim
