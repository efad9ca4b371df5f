// Loads settings from a YAML file without ROS (ROS-free, yaml-cpp): the cores' tests and the offline tools
// run the shipped configuration through this, with the same checks as the node's loader. A nested
// mapping's keys are joined with '/', as on the parameter server.
#pragma once

#include <yaml-cpp/yaml.h>

#include <map>
#include <set>
#include <string>

#include "docking_settings/config_error.h"
#include "docking_settings/setting_info.h"

namespace docking_settings {

/// The file's keys, nested mappings joined with '/'; throws ConfigError when it cannot be read.
std::map<std::string, YAML::Node> readYamlKeys(const std::string& path);

template <typename T>
T convertYaml(const YAML::Node& node, const std::string& where) {
  try {
    return node.as<T>();
  } catch (const YAML::Exception&) {
    throw ConfigError(where, ConfigProblem::kWrongType, "cannot read '" + YAML::Dump(node) + "' as its declared type");
  }
}

/// Applies the file's values over `settings` (which start at their declared defaults); returns the keys
/// of the file that no setting reads. Throws ConfigError for a wrong type or a value not allowed.
template <typename Settings>
std::set<std::string> loadSettingsYaml(const std::string& path, Settings& settings) {
  const auto keys = readYamlKeys(path);
  std::set<std::string> unread;
  for (const auto& entry : keys) unread.insert(entry.first);
  visitSettings(settings, [&](const SettingInfo& info, const std::string& key, auto& field) {
    const auto found = keys.find(key);
    if (found == keys.end()) return;
    using T = std::decay_t<decltype(field)>;
    const std::string where = path + ": " + key;
    T value = convertYaml<T>(found->second, where);
    requireAllowed(info, where, value);
    field = std::move(value);
    unread.erase(key);
  });
  return unread;
}

/// The declared defaults with the shipped file's overrides: what the node runs. Throws ConfigError also for
/// a key of the file that no setting reads (a core test must not run a configuration the node refuses).
template <typename Settings>
Settings shippedSettings(const std::string& path) {
  Settings settings;
  const auto unread = loadSettingsYaml(path, settings);
  if (!unread.empty()) throw ConfigError(path + ": " + *unread.begin(), ConfigProblem::kInvalid, "no setting reads it");
  return settings;
}

}  // namespace docking_settings
