// dynamic_reconfigure for declared settings: the .cfg adds the live settings from the declaration
// (docking_settings.reconfigure.add_live_settings), and a node applies a new configuration with one call,
// whatever its settings: no forward and reverse copies per parameter.
#pragma once

#include <dynamic_reconfigure/Config.h>

#include <string>
#include <type_traits>
#include <vector>

#include "docking_settings/setting_info.h"

namespace docking_settings {

namespace detail {

template <typename Entry, typename T>
bool assignFrom(const std::vector<Entry>& entries, const std::string& key, T* field) {
  for (const auto& entry : entries) {
    if (entry.name == key) {
      *field = static_cast<T>(entry.value);
      return true;
    }
  }
  return false;
}

}  // namespace detail

/// Copies every live setting present in `config` (dynamic_reconfigure's message form of a configuration:
/// XConfig::__toMessage__) into `settings`; returns how many it copied.
template <typename Settings>
int applyReconfigure(const dynamic_reconfigure::Config& config, Settings& settings) {
  int applied = 0;
  visitSettings(settings, [&](const SettingInfo& info, const std::string& key, auto& field) {
    using T = std::decay_t<decltype(field)>;
    if (!info.live) return;
    if constexpr (std::is_same_v<T, bool>) {
      applied += detail::assignFrom(config.bools, key, &field);
    } else if constexpr (std::is_same_v<T, int>) {
      applied += detail::assignFrom(config.ints, key, &field);
    } else if constexpr (std::is_same_v<T, double>) {
      applied += detail::assignFrom(config.doubles, key, &field);
    } else if constexpr (std::is_same_v<T, std::string>) {
      applied += detail::assignFrom(config.strs, key, &field);
    }
  });
  return applied;
}

/// The live settings of `settings` as dynamic_reconfigure's message (XConfig::__fromMessage__ takes it):
/// how a node shows the values in force after refusing a new combination.
template <typename Settings>
dynamic_reconfigure::Config toReconfigure(Settings settings) {
  dynamic_reconfigure::Config config;
  visitSettings(settings, [&](const SettingInfo& info, const std::string& key, auto& field) {
    using T = std::decay_t<decltype(field)>;
    if (!info.live) return;
    if constexpr (std::is_same_v<T, bool>) {
      config.bools.emplace_back();
      config.bools.back().name = key;
      config.bools.back().value = field;
    } else if constexpr (std::is_same_v<T, int>) {
      config.ints.emplace_back();
      config.ints.back().name = key;
      config.ints.back().value = field;
    } else if constexpr (std::is_same_v<T, double>) {
      config.doubles.emplace_back();
      config.doubles.back().name = key;
      config.doubles.back().value = field;
    } else if constexpr (std::is_same_v<T, std::string>) {
      config.strs.emplace_back();
      config.strs.back().name = key;
      config.strs.back().value = field;
    }
  });
  return config;
}

}  // namespace docking_settings
