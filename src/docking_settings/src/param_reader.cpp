#include "docking_settings/param_reader.h"

#include <cmath>
#include <sstream>

namespace docking_settings {
namespace {

bool isNumber(const XmlRpc::XmlRpcValue& v) {
  return v.getType() == XmlRpc::XmlRpcValue::TypeDouble || v.getType() == XmlRpc::XmlRpcValue::TypeInt;
}

double numberOf(const XmlRpc::XmlRpcValue& v) {
  XmlRpc::XmlRpcValue copy = v;  // the accessors are not const
  return v.getType() == XmlRpc::XmlRpcValue::TypeInt ? static_cast<double>(static_cast<int>(copy))
                                                      : static_cast<double>(copy);
}

template <typename T>
bool convertList(const XmlRpc::XmlRpcValue& value, std::vector<T>* out) {
  if (value.getType() != XmlRpc::XmlRpcValue::TypeArray) return false;
  XmlRpc::XmlRpcValue copy = value;
  std::vector<T> result(static_cast<std::size_t>(copy.size()));
  for (int i = 0; i < copy.size(); ++i) {
    if (!convertValue(copy[i], &result[static_cast<std::size_t>(i)])) return false;
  }
  *out = std::move(result);
  return true;
}

std::string formatNumber(double v) {
  std::ostringstream s;
  s << v;
  return s.str();
}

}  // namespace

std::string describeValue(const XmlRpc::XmlRpcValue& value) {
  XmlRpc::XmlRpcValue copy = value;
  switch (value.getType()) {
    case XmlRpc::XmlRpcValue::TypeBoolean: return std::string("the boolean ") + (static_cast<bool>(copy) ? "true" : "false");
    case XmlRpc::XmlRpcValue::TypeInt: return "the integer " + std::to_string(static_cast<int>(copy));
    case XmlRpc::XmlRpcValue::TypeDouble: return "the number " + formatNumber(static_cast<double>(copy));
    case XmlRpc::XmlRpcValue::TypeString: return "the string '" + static_cast<std::string>(copy) + "'";
    case XmlRpc::XmlRpcValue::TypeArray: return "a list of " + std::to_string(copy.size()) + " entries";
    case XmlRpc::XmlRpcValue::TypeStruct: return "a dictionary";
    default: return "a value of another kind";
  }
}

bool convertValue(const XmlRpc::XmlRpcValue& value, double* out) {
  if (!isNumber(value)) return false;
  *out = numberOf(value);
  return true;
}

bool convertValue(const XmlRpc::XmlRpcValue& value, int* out) {
  if (value.getType() != XmlRpc::XmlRpcValue::TypeInt) return false;
  XmlRpc::XmlRpcValue copy = value;
  *out = static_cast<int>(copy);
  return true;
}

bool convertValue(const XmlRpc::XmlRpcValue& value, bool* out) {
  if (value.getType() != XmlRpc::XmlRpcValue::TypeBoolean) return false;
  XmlRpc::XmlRpcValue copy = value;
  *out = static_cast<bool>(copy);
  return true;
}

bool convertValue(const XmlRpc::XmlRpcValue& value, std::string* out) {
  XmlRpc::XmlRpcValue copy = value;
  if (value.getType() == XmlRpc::XmlRpcValue::TypeInt) {  // YAML's 0 for a device "0": a string takes its text
    *out = std::to_string(static_cast<int>(copy));
    return true;
  }
  if (value.getType() != XmlRpc::XmlRpcValue::TypeString) return false;
  *out = static_cast<std::string>(copy);
  return true;
}

bool convertValue(const XmlRpc::XmlRpcValue& value, std::vector<double>* out) { return convertList(value, out); }
bool convertValue(const XmlRpc::XmlRpcValue& value, std::vector<int>* out) { return convertList(value, out); }
bool convertValue(const XmlRpc::XmlRpcValue& value, std::vector<std::string>* out) { return convertList(value, out); }

bool convertValue(const XmlRpc::XmlRpcValue& value, XmlRpc::XmlRpcValue* out) {
  *out = value;
  return true;
}

template <> const char* typeName<double>() { return "a number"; }
template <> const char* typeName<int>() { return "an integer"; }
template <> const char* typeName<bool>() { return "a boolean (true or false)"; }
template <> const char* typeName<std::string>() { return "a string"; }
template <> const char* typeName<std::vector<double>>() { return "a list of numbers"; }
template <> const char* typeName<std::vector<int>>() { return "a list of integers"; }
template <> const char* typeName<std::vector<std::string>>() { return "a list of strings"; }
template <> const char* typeName<XmlRpc::XmlRpcValue>() { return "a value"; }

void ParamReader::checkRange(const std::string& key, double value, double min, double max,
                             const std::string& index) const {
  if (std::isfinite(value) && value >= min && value <= max) return;
  throw ConfigError(resolved(key) + index, ConfigProblem::kOutOfRange,
                    formatNumber(value) + " is outside [" + formatNumber(min) + ", " + formatNumber(max) + "]");
}

std::vector<double> ParamReader::requireListInRange(const std::string& key, std::size_t size, double min,
                                                    double max) const {
  const auto values = require<std::vector<double>>(key);
  if (size != 0 && values.size() != size) {
    throw ConfigError(resolved(key), ConfigProblem::kWrongSize,
                      "expected " + std::to_string(size) + " entries, got " + std::to_string(values.size()));
  }
  for (std::size_t i = 0; i < values.size(); ++i) checkRange(key, values[i], min, max, "[" + std::to_string(i) + "]");
  return values;
}

}  // namespace docking_settings
