#include "docking_settings/setting_info.h"

#include <algorithm>
#include <sstream>

namespace docking_settings {
namespace {

std::string formatNumber(double v) {
  std::ostringstream s;
  s << v;
  return s.str();
}

}  // namespace

std::optional<ValueProblem> valueProblem(const SettingInfo& info, double value) {
  if (std::isfinite(value) && value >= info.min && value <= info.max) return std::nullopt;
  return ValueProblem{ConfigProblem::kOutOfRange, formatNumber(value) + " is outside [" + formatNumber(info.min) +
                                                      ", " + formatNumber(info.max) + "]"};
}

std::optional<ValueProblem> valueProblem(const SettingInfo& info, int value) {
  return valueProblem(info, static_cast<double>(value));
}

std::optional<ValueProblem> valueProblem(const SettingInfo&, bool) { return std::nullopt; }

std::optional<ValueProblem> valueProblem(const SettingInfo& info, const std::string& value) {
  if (info.choices.empty() || std::find(info.choices.begin(), info.choices.end(), value) != info.choices.end()) {
    return std::nullopt;
  }
  std::string allowed;
  for (const auto& c : info.choices) allowed += (allowed.empty() ? "" : ", ") + c;
  return ValueProblem{ConfigProblem::kInvalid, "'" + value + "' is not one of " + allowed};
}

}  // namespace docking_settings
