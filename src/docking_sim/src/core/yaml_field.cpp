#include "yaml_field.h"

#include <fstream>
#include <sstream>

namespace docking_sim {

YamlField YamlField::open(const std::string& path) {
  std::ifstream in(path);
  if (!in) throw ConfigError(path, "", "cannot open the file");
  try {
    YAML::Node root = YAML::LoadFile(path);
    if (!root.IsMap()) throw ConfigError(path, "", "expected a YAML map at the top level");
    return YamlField(root, path, "");
  } catch (const YAML::Exception& e) {
    throw ConfigError(path, "", std::string("not valid YAML: ") + e.what());
  }
}

YamlField YamlField::operator[](const std::string& key) const {
  requireDefined();
  if (!node_.IsMap()) fail("expected a map");
  const YAML::Node& const_node = node_;  // const access: never inserts
  return YamlField(const_node[key], file_, name_.empty() ? key : name_ + "." + key);
}

YamlField YamlField::at(std::size_t index) const {
  requireDefined();
  if (!node_.IsSequence()) fail("expected a list");
  if (index >= node_.size()) fail("has no element " + std::to_string(index));
  const YAML::Node& const_node = node_;
  return YamlField(const_node[index], file_, name_ + "[" + std::to_string(index) + "]");
}

bool YamlField::has(const std::string& key) const {
  if (!node_.IsDefined() || !node_.IsMap()) return false;
  const YAML::Node& const_node = node_;
  return const_node[key].IsDefined() && !const_node[key].IsNull();
}

std::size_t YamlField::size() const {
  requireDefined();
  if (!node_.IsSequence()) fail("expected a list");
  return node_.size();
}

std::vector<std::string> YamlField::keys() const {
  requireDefined();
  if (!node_.IsMap()) fail("expected a map");
  std::vector<std::string> out;
  for (const auto& kv : node_) out.push_back(kv.first.as<std::string>());
  return out;
}

void YamlField::requireDefined() const {
  if (!node_.IsDefined() || node_.IsNull()) fail("missing");
}

void YamlField::fail(const std::string& problem) const { throw ConfigError(file_, name_, problem); }

double YamlField::asDouble() const {
  requireDefined();
  if (!node_.IsScalar()) fail("expected a number");
  double value = 0.0;
  try {
    value = node_.as<double>();
  } catch (const YAML::Exception&) {
    fail("expected a number, got '" + node_.Scalar() + "'");
  }
  if (!std::isfinite(value)) fail("must be finite");
  return value;
}

double YamlField::asDouble(double min, double max) const {
  const double value = asDouble();
  if (value < min || value > max) {
    std::ostringstream msg;
    msg << "must be within [" << min << ", " << max << "], got " << value;
    fail(msg.str());
  }
  return value;
}

double YamlField::asPositive() const {
  const double value = asDouble();
  if (!(value > 0.0)) fail("must be > 0, got " + std::to_string(value));
  return value;
}

long long YamlField::asInteger(long long min, long long max) const {
  requireDefined();
  if (!node_.IsScalar()) fail("expected an integer");
  long long value = 0;
  try {
    value = node_.as<long long>();
  } catch (const YAML::Exception&) {
    fail("expected an integer, got '" + node_.Scalar() + "'");
  }
  if (value < min || value > max) {
    fail("must be within [" + std::to_string(min) + ", " + std::to_string(max) + "], got " + std::to_string(value));
  }
  return value;
}

std::string YamlField::asString() const {
  requireDefined();
  if (!node_.IsScalar()) fail("expected a string");
  return node_.Scalar();
}

bool YamlField::asBool() const {
  requireDefined();
  try {
    return node_.as<bool>();
  } catch (const YAML::Exception&) {
    fail("expected true or false");
  }
}

std::vector<double> YamlField::asVector(std::size_t expected_size) const {
  const std::size_t n = size();
  if (n != expected_size) fail("expected " + std::to_string(expected_size) + " numbers, got " + std::to_string(n));
  std::vector<double> out;
  for (std::size_t i = 0; i < n; ++i) out.push_back(at(i).asDouble());
  return out;
}

}  // namespace docking_sim
