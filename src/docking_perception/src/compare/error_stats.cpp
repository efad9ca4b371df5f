#include "error_stats.h"

#include <algorithm>
#include <cmath>
#include <limits>

#include "docking_perception/mono/pose_types.h"

namespace docking_perception {
namespace compare {

double percentile(std::vector<double> values, double q) {
  if (values.empty()) return std::numeric_limits<double>::quiet_NaN();
  std::sort(values.begin(), values.end());
  const double pos = std::clamp(q, 0.0, 1.0) * static_cast<double>(values.size() - 1);
  const std::size_t lo = static_cast<std::size_t>(std::floor(pos));
  const std::size_t hi = std::min(lo + 1, values.size() - 1);
  const double f = pos - static_cast<double>(lo);
  return values[lo] * (1.0 - f) + values[hi] * f;
}

double rotationErrorDeg(const Eigen::Matrix3d& a, const Eigen::Matrix3d& b) {
  return mono::rotationAngleBetween(a, b) * 180.0 / M_PI;
}

}  // namespace compare
}  // namespace docking_perception
