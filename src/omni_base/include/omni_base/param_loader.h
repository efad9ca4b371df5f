// Reading and validating a node's parameters: a missing or invalid one stops the node with a
// message that names it.
#pragma once

#include <ros/ros.h>

#include <cmath>
#include <stdexcept>
#include <string>
#include <vector>

#include "omni_base/parameter_ranges.h"

namespace omni_base {

class ParamLoader {
 public:
  explicit ParamLoader(const ros::NodeHandle& nh) : nh_(nh) {}

  template <typename T>
  T require(const std::string& name) const {
    T value;
    if (!nh_.getParam(name, value)) {
      throw std::runtime_error("parameter " + nh_.resolveName(name) + " is missing or has the wrong type");
    }
    return value;
  }

  template <typename T>
  T optional(const std::string& name, const T& fallback) const {
    T value;
    return nh_.getParam(name, value) ? value : fallback;
  }

  std::vector<double> requireVector(const std::string& name, std::size_t size, bool positive) const {
    const auto v = require<std::vector<double>>(name);
    if (size != 0 && v.size() != size) {
      throw std::runtime_error("parameter " + nh_.resolveName(name) + " must have " + std::to_string(size) +
                               " entries, has " + std::to_string(v.size()));
    }
    for (double x : v) {
      if (!std::isfinite(x) || (positive && !(x > 0.0))) {
        throw std::runtime_error("parameter " + nh_.resolveName(name) + " has an invalid entry " + std::to_string(x));
      }
    }
    return v;
  }

  /// A number within its range in parameterRanges() (the one home of the bounds).
  double requireInRange(const std::string& name) const {
    const double v = require<double>(name);
    throwIfOutOfRange(name, v);
    return v;
  }

  int requireIntInRange(const std::string& name) const {
    const int v = require<int>(name);
    throwIfOutOfRange(name, v);
    return v;
  }

  /// A list whose every entry is within the range of `name`.
  std::vector<double> requireVectorInRange(const std::string& name, std::size_t size) const {
    const auto v = requireVector(name, size, false);
    for (std::size_t i = 0; i < v.size(); ++i) throwIfOutOfRange(name, v[i], "[" + std::to_string(i) + "]");
    return v;
  }

  std::string name(const std::string& param) const { return nh_.resolveName(param); }

 private:
  void throwIfOutOfRange(const std::string& name, double value, const std::string& index = "") const {
    if (const auto error = checkParameterRange(name, value, nh_.resolveName(name) + index)) {
      throw std::runtime_error(*error);
    }
  }

  ros::NodeHandle nh_;
};

}  // namespace omni_base
