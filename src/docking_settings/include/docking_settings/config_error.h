// A configuration error: which key, and what is wrong with it, as a code (ROS-free). Every loader of the
// workspace throws this, so a node (and its tests) can tell a configuration error, which no restart
// cures, from a failure at run time.
#pragma once

#include <cstdint>
#include <stdexcept>
#include <string>

namespace docking_settings {

enum class ConfigProblem : std::uint8_t {
  kMissing = 1,     ///< the key is not set
  kWrongType = 2,   ///< set, but not of the declared type (a string where a number belongs)
  kOutOfRange = 3,  ///< a number outside its declared range
  kWrongSize = 4,   ///< a list of the wrong length
  kInvalid = 5,     ///< a value the setting does not allow (an unknown name, two settings that contradict)
};
const char* configProblemName(ConfigProblem problem);

/// An invalid argument of a particular kind: the cores' validators throw it too.
class ConfigError : public std::invalid_argument {
 public:
  /// `key`: the resolved parameter name; `detail`: what was found and what was expected.
  ConfigError(std::string key, ConfigProblem problem, const std::string& detail)
      : std::invalid_argument(std::string("parameter ") + key + ": " + configProblemName(problem) + ": " + detail),
        key_(std::move(key)),
        problem_(problem),
        detail_(detail) {}
  const std::string& key() const { return key_; }
  ConfigProblem problem() const { return problem_; }
  const std::string& detail() const { return detail_; }

 private:
  std::string key_;
  ConfigProblem problem_;
  std::string detail_;
};

inline const char* configProblemName(ConfigProblem problem) {
  switch (problem) {
    case ConfigProblem::kMissing: return "missing";
    case ConfigProblem::kWrongType: return "wrong type";
    case ConfigProblem::kOutOfRange: return "out of range";
    case ConfigProblem::kWrongSize: return "wrong size";
    case ConfigProblem::kInvalid: return "invalid";
  }
  return "invalid";
}

}  // namespace docking_settings
