// A YAML node that knows its file and its dotted path, so that every error names both (private).
#pragma once

#include <yaml-cpp/yaml.h>

#include <cmath>
#include <string>
#include <vector>

#include "docking_sim/config_error.h"

namespace docking_sim {

class YamlField {
 public:
  /// Opens a file; a missing or unparsable file throws ConfigError naming it.
  static YamlField open(const std::string& path);

  YamlField(const YAML::Node& node, std::string file, std::string name)
      : node_(node), file_(std::move(file)), name_(std::move(name)) {}

  YamlField operator[](const std::string& key) const;
  YamlField at(std::size_t index) const;
  bool has(const std::string& key) const;
  bool isMap() const { return node_.IsMap(); }
  std::size_t size() const;  ///< sequence length (throws unless a sequence)
  std::vector<std::string> keys() const;  ///< map keys in file order

  double asDouble() const;
  /// A finite number within [min, max].
  double asDouble(double min, double max) const;
  /// A finite number > 0.
  double asPositive() const;
  long long asInteger(long long min, long long max) const;
  std::string asString() const;
  bool asBool() const;
  std::vector<double> asVector(std::size_t expected_size) const;

  [[noreturn]] void fail(const std::string& problem) const;
  const std::string& name() const { return name_; }
  const std::string& file() const { return file_; }

 private:
  void requireDefined() const;
  YAML::Node node_;
  std::string file_;
  std::string name_;
};

}  // namespace docking_sim
