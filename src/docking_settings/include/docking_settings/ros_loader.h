// Loads a node's settings from its parameter server namespace: the one loader of the workspace. Every
// declared setting starts at its declared default (the generated struct's initialiser); a key set on the
// parameter server (the shipped YAML holds only what differs from the defaults) replaces it, read with its
// type checked and validated against its declaration. A problem throws ConfigError naming the key.
#pragma once

#include <ros/ros.h>

#include <set>
#include <string>

#include "docking_settings/param_reader.h"
#include "docking_settings/setting_info.h"

namespace docking_settings {

/// Loads every setting of `settings` that `nh` has a parameter for; returns the keys it read.
template <typename Settings>
std::set<std::string> loadSettings(const ros::NodeHandle& nh, Settings& settings) {
  const ParamReader reader(nh);
  std::set<std::string> read;
  visitSettings(settings, [&](const SettingInfo& info, const std::string& key, auto& field) {
    using T = std::decay_t<decltype(field)>;
    if (!nh.hasParam(key)) return;
    T value = reader.require<T>(key);
    requireAllowed(info, reader.resolved(key), value);
    field = std::move(value);
    read.insert(key);
  });
  return read;
}

/// Warns (once, naming them) about keys in `nh`'s namespace that no declared setting reads: a typo in a
/// user's YAML would otherwise leave the default in force without a word. `also_read`: keys of the
/// namespace that the node reads apart from its settings (robot data, launch arguments).
template <typename Settings>
void warnUnknownKeys(const ros::NodeHandle& nh, Settings& settings, const std::set<std::string>& also_read = {}) {
  std::set<std::string> declared = also_read;
  visitSettings(settings, [&](const SettingInfo&, const std::string& key, auto&) { declared.insert(key); });
  std::vector<std::string> names;
  nh.getParamNames(names);
  const std::string ns = nh.getNamespace() + "/";
  for (const auto& name : names) {
    if (name.rfind(ns, 0) != 0) continue;
    const std::string key = name.substr(ns.size());
    bool known = declared.count(key) > 0;
    for (const auto& d : declared) known = known || key.rfind(d + "/", 0) == 0;  // inside a declared dictionary
    if (!known) ROS_WARN("%s: parameter %s is not a setting of this node: ignored", ns.c_str(), name.c_str());
  }
}

}  // namespace docking_settings
