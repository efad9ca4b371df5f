// Reads a node's parameters from the parameter server with their types checked: the one loader of the
// workspace. A missing key, a value of the wrong type and a number out of its range each throw a
// ConfigError that names the resolved key and the problem (ros::NodeHandle::getParam alone reports a
// string where a number belongs as "missing").
#pragma once

#include <ros/ros.h>

#include <stdexcept>
#include <string>
#include <vector>

#include "docking_settings/config_error.h"

namespace docking_settings {

/// What a parameter server value is, for a message: "the string 'abc'", "a list of 2 entries".
std::string describeValue(const XmlRpc::XmlRpcValue& value);

/// Converts a parameter server value to T; false when it is not of that type. Integers are numbers too
/// (`rate: 50` for a double), but not the other way round.
bool convertValue(const XmlRpc::XmlRpcValue& value, double* out);
bool convertValue(const XmlRpc::XmlRpcValue& value, int* out);
bool convertValue(const XmlRpc::XmlRpcValue& value, bool* out);
bool convertValue(const XmlRpc::XmlRpcValue& value, std::string* out);
bool convertValue(const XmlRpc::XmlRpcValue& value, std::vector<double>* out);
bool convertValue(const XmlRpc::XmlRpcValue& value, std::vector<int>* out);
bool convertValue(const XmlRpc::XmlRpcValue& value, std::vector<std::string>* out);
bool convertValue(const XmlRpc::XmlRpcValue& value, XmlRpc::XmlRpcValue* out);  ///< as it is (a structure)

/// The type a parameter must have, for a message ("a number").
template <typename T>
const char* typeName();
template <> const char* typeName<double>();
template <> const char* typeName<int>();
template <> const char* typeName<bool>();
template <> const char* typeName<std::string>();
template <> const char* typeName<std::vector<double>>();
template <> const char* typeName<std::vector<int>>();
template <> const char* typeName<std::vector<std::string>>();
template <> const char* typeName<XmlRpc::XmlRpcValue>();

class ParamReader {
 public:
  explicit ParamReader(const ros::NodeHandle& nh) : nh_(nh) {}

  /// The value of `key`; throws ConfigError (missing, wrong type).
  template <typename T>
  T require(const std::string& key) const {
    XmlRpc::XmlRpcValue raw;
    if (!nh_.getParam(key, raw)) throw ConfigError(resolved(key), ConfigProblem::kMissing, "not set");
    T value;
    if (!convertValue(raw, &value)) {
      throw ConfigError(resolved(key), ConfigProblem::kWrongType,
                        std::string("expected ") + typeName<T>() + ", got " + describeValue(raw));
    }
    return value;
  }

  /// The value of `key` if it is set (of the right type, else ConfigError), else `fallback`.
  template <typename T>
  T optional(const std::string& key, const T& fallback) const {
    return nh_.hasParam(key) ? require<T>(key) : fallback;
  }

  /// A number within [min, max]; throws ConfigError (missing, wrong type, out of range).
  template <typename T>
  T requireInRange(const std::string& key, T min, T max) const {
    const T value = require<T>(key);
    checkRange(key, static_cast<double>(value), static_cast<double>(min), static_cast<double>(max));
    return value;
  }

  /// A list of `size` entries (0: any), each within [min, max].
  std::vector<double> requireListInRange(const std::string& key, std::size_t size, double min, double max) const;

  /// Throws ConfigError (out of range) naming `key` when `value` lies outside [min, max] or is not finite.
  void checkRange(const std::string& key, double value, double min, double max, const std::string& index = "") const;

  /// A value the setting does not allow (an unknown name, two settings that contradict).
  [[noreturn]] void invalid(const std::string& key, const std::string& why) const {
    throw ConfigError(resolved(key), ConfigProblem::kInvalid, why);
  }

  /// Runs a core's validation of the loaded settings: a ConfigError naming a key relative to the node gets
  /// the resolved key; another std::invalid_argument (whose message names the field) becomes a ConfigError
  /// on this node's namespace.
  template <typename Validate>
  void validated(Validate&& validate) const {
    try {
      validate();
    } catch (const ConfigError& e) {
      if (!e.key().empty() && e.key()[0] == '/') throw;
      throw ConfigError(resolved(e.key()), e.problem(), e.detail());
    } catch (const std::invalid_argument& e) {
      throw ConfigError(nh_.getNamespace(), ConfigProblem::kInvalid, e.what());
    }
  }

  std::string resolved(const std::string& key) const { return nh_.resolveName(key); }
  const ros::NodeHandle& nodeHandle() const { return nh_; }

 private:
  ros::NodeHandle nh_;
};

}  // namespace docking_settings
