#include "docking_settings/yaml_loader.h"

namespace docking_settings {
namespace {

void flatten(const YAML::Node& node, const std::string& prefix, std::map<std::string, YAML::Node>* out) {
  for (const auto& entry : node) {
    const std::string key = prefix + entry.first.as<std::string>();
    if (entry.second.IsMap()) {
      flatten(entry.second, key + "/", out);
    } else {
      (*out)[key] = entry.second;
    }
  }
}

}  // namespace

std::map<std::string, YAML::Node> readYamlKeys(const std::string& path) {
  YAML::Node root;
  try {
    root = YAML::LoadFile(path);
  } catch (const YAML::Exception& e) {
    throw ConfigError(path, ConfigProblem::kInvalid, std::string("cannot read the file: ") + e.what());
  }
  std::map<std::string, YAML::Node> keys;
  if (root.IsMap()) flatten(root, "", &keys);
  return keys;
}

}  // namespace docking_settings
