// What a settings declaration says of one setting, as the generated visitSettings() hands it to a
// visitor (ROS-free). Loaders, validators and dynamic_reconfigure are written once against it.
#pragma once

#include <cmath>
#include <optional>
#include <string>
#include <vector>

#include "docking_settings/config_error.h"

namespace docking_settings {

enum class SettingType { kDouble, kInt, kBool, kString, kDoubleList, kIntList, kStringList };

struct SettingInfo {
  const char* name;        ///< the field's name (the key without its struct's prefix)
  SettingType type;
  double min;              ///< numbers, and each entry of a number list
  double max;
  int size;                ///< lists: the required length (0: any)
  const char* unit;
  const char* doc;         ///< one line: what it does, what it guards against
  bool live;               ///< changeable while running (dynamic_reconfigure)
  const char* testbed;     ///< non-empty: holds only for the floor test bed or the simulator, and why
  const char* default_text;
  std::vector<std::string> choices;  ///< strings: the allowed values (empty: any)
};

/// Why a value is not allowed by its declaration: a code and the words.
struct ValueProblem {
  ConfigProblem problem;
  std::string detail;
};

/// What is wrong with `value` under `info` (range, list length, choices), or nothing.
std::optional<ValueProblem> valueProblem(const SettingInfo& info, double value);
std::optional<ValueProblem> valueProblem(const SettingInfo& info, int value);
std::optional<ValueProblem> valueProblem(const SettingInfo& info, bool value);
std::optional<ValueProblem> valueProblem(const SettingInfo& info, const std::string& value);
template <typename T>
std::optional<ValueProblem> valueProblem(const SettingInfo& info, const std::vector<T>& values) {
  if (info.size > 0 && static_cast<int>(values.size()) != info.size) {
    return ValueProblem{ConfigProblem::kWrongSize,
                        "expected " + std::to_string(info.size) + " entries, got " + std::to_string(values.size())};
  }
  for (std::size_t i = 0; i < values.size(); ++i) {
    if (auto problem = valueProblem(info, values[i])) {
      problem->detail = "[" + std::to_string(i) + "] " + problem->detail;
      return problem;
    }
  }
  return std::nullopt;
}

/// Throws ConfigError naming `key` when `value` is not allowed by `info`.
template <typename T>
void requireAllowed(const SettingInfo& info, const std::string& key, const T& value) {
  if (auto problem = valueProblem(info, value)) throw ConfigError(key, problem->problem, problem->detail);
}

/// Throws ConfigError for the first setting of `settings` that its declaration does not allow: the cores'
/// validators start with this, and add only what one setting's range cannot say (two that contradict).
template <typename Settings>
void validateSettings(Settings settings) {  // a copy: visitSettings() hands out mutable fields
  visitSettings(settings, [](const SettingInfo& info, const std::string& key, const auto& field) {
    requireAllowed(info, key, field);
  });
}

}  // namespace docking_settings
