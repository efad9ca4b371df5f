// Numbers in the disparity stage's reasons and validation messages (private to the disparity core).
#pragma once

#include <sstream>
#include <string>

namespace docking_perception {
namespace disparity {

// `value` with a few significant digits: enough to see what decided, short enough for a status line.
inline std::string formatNumber(double value, int significant_digits = 4) {
  std::ostringstream stream;
  stream.precision(significant_digits);
  stream << value;
  return stream.str();
}

}  // namespace disparity
}  // namespace docking_perception
