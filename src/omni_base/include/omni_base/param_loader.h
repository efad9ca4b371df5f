// Reading and validating the node's parameters: the workspace's reader (docking_settings: a missing
// key, a wrong type and a value out of range each stop the node once, naming the key) with the bounds of
// parameter_ranges.h, the one home of omni_base's ranges.
#pragma once

#include <docking_settings/param_reader.h>

#include <cmath>
#include <string>
#include <vector>

#include "omni_base/parameter_ranges.h"

namespace omni_base {

class ParamLoader {
 public:
  explicit ParamLoader(const ros::NodeHandle& nh) : reader_(nh) {}

  template <typename T>
  T require(const std::string& name) const {
    return reader_.require<T>(name);
  }

  template <typename T>
  T optional(const std::string& name, const T& fallback) const {
    return reader_.optional<T>(name, fallback);
  }

  /// A list of `size` finite entries (0: any size), each positive when `positive`.
  std::vector<double> requireVector(const std::string& name, std::size_t size, bool positive) const {
    return reader_.requireListInRange(name, size, positive ? std::nextafter(0.0, 1.0) : -HUGE_VAL, HUGE_VAL);
  }

  /// A number within its range in parameterRanges().
  double requireInRange(const std::string& name) const {
    const ParameterRange& range = parameterRange(name);
    return reader_.requireInRange<double>(name, range.min, range.max);
  }

  int requireIntInRange(const std::string& name) const {
    const ParameterRange& range = parameterRange(name);
    return reader_.requireInRange<int>(name, static_cast<int>(range.min), static_cast<int>(range.max));
  }

  /// A list whose every entry is within the range of `name`.
  std::vector<double> requireVectorInRange(const std::string& name, std::size_t size) const {
    const ParameterRange& range = parameterRange(name);
    return reader_.requireListInRange(name, size, range.min, range.max);
  }

  /// A value the parameter does not allow (two parameters that contradict, an unknown name).
  [[noreturn]] void invalid(const std::string& name, const std::string& why) const {
    throw docking_settings::ConfigError(reader_.resolved(name), docking_settings::ConfigProblem::kInvalid, why);
  }

  std::string name(const std::string& param) const { return reader_.resolved(param); }

 private:
  docking_settings::ParamReader reader_;
};

}  // namespace omni_base
