// The allowed range of every safety-relevant omni_base parameter (ROS-free). The node's and the fake
// board's loaders validate against this table at start-up; the README's parameter table lists the
// same ranges (a gtest checks that it does).
#pragma once

#include <optional>
#include <string>
#include <vector>

namespace omni_base {

struct ParameterRange {
  const char* name;  ///< relative to the node's private namespace, as in config/omni_base.yaml
  double min;
  double max;
  const char* why;   ///< what the bounds protect
};

/// Every bounded parameter. For a list parameter (limits/*, wheels/drive_angles_deg) each entry is bounded.
const std::vector<ParameterRange>& parameterRanges();

/// The table's entry for name; throws std::out_of_range for a name the table does not hold.
const ParameterRange& parameterRange(const std::string& name);

/// Empty when value is finite and within the range of `name`; otherwise an error that names the
/// parameter (as displayed_name, e.g. the resolved ROS name), the value and the allowed range.
std::optional<std::string> checkParameterRange(const std::string& name, double value, const std::string& displayed_name);

/// "min .. max" as the README's parameter table writes it.
std::string formatRange(const ParameterRange& range);

}  // namespace omni_base
