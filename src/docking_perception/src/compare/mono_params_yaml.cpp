#include "mono_params_yaml.h"

#include <yaml-cpp/yaml.h>

#include "docking_perception/mono/mono_pose_param_keys.h"

#include <vector>

namespace docking_perception {
namespace compare {
namespace {

template <typename T>
bool read(const YAML::Node& root, const std::string& key, T* value, std::string* error) {
  const YAML::Node node = root[key];
  if (!node) {
    *error = "missing parameter '" + key + "'";
    return false;
  }
  try {
    *value = node.as<T>();
  } catch (const YAML::Exception&) {
    *error = "mistyped parameter '" + key + "'";
    return false;
  }
  return true;
}

}  // namespace

bool loadMonoParams(const std::string& yaml_path, mono::MonoPoseParams* params, std::string* error) {
  YAML::Node root;
  try {
    root = YAML::LoadFile(yaml_path);
  } catch (const YAML::Exception& e) {
    *error = yaml_path + ": " + e.what();
    return false;
  }
  mono::MonoPoseParams p;
  std::string mode, solver, velocity;
  std::string e;
  bool ok = read(root, "mode", &mode, &e) && read(root, "solver", &solver, &e) &&
            read(root, "velocity_method", &velocity, &e);
  mono::visitMonoPoseParams(p, [&](const char* key, auto* field) { ok = ok && read(root, key, field, &e); });
  if (!ok) {
    *error = yaml_path + ": " + e;
    return false;
  }
  if (!mono::parseMonoMode(mode, &p.mode) || !mono::parsePoseSolver(solver, &p.solver) ||
      !mono::parseVelocityMethod(velocity, &p.velocity)) {
    *error = yaml_path + ": unknown mode, solver or velocity_method";
    return false;
  }
  p.pnp.min_pixel_sigma = p.min_pixel_sigma;
  const std::string invalid = mono::validateParams(p);
  if (!invalid.empty()) {
    *error = yaml_path + ": " + invalid;
    return false;
  }
  *params = p;
  return true;
}

}  // namespace compare
}  // namespace docking_perception
