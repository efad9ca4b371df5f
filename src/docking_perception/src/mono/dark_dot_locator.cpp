#include "docking_perception/mono/dark_dot_locator.h"

#include <algorithm>
#include <cmath>
#include <vector>

namespace docking_perception {
namespace mono {
namespace {

// The search disc is at least this wide (a far dot is a few pixels), and the refined centre may move at
// most one dot radius (+1 px) from the prediction: farther, it is something else.
constexpr double kMinSearchRadiusPx = 3.0;
constexpr double kMaxShiftInRadii = 1.0;

}  // namespace

bool DarkDotLocator::locate(const cv::Mat& gray, const Eigen::Vector2d& predicted, double radius_px,
                            Eigen::Vector2d* centre, std::string* reason) const {
  if (gray.empty() || gray.type() != CV_8UC1) {
    if (reason) *reason = "image is not 8-bit gray";
    return false;
  }
  const double search_radius = std::max(kMinSearchRadiusPx, params_.search_radius_factor * radius_px);
  Eigen::Vector2d current = predicted;
  std::vector<uint8_t> values;
  for (int iteration = 0; iteration < 2; ++iteration) {
    const int x0 = static_cast<int>(std::floor(current.x() - search_radius));
    const int y0 = static_cast<int>(std::floor(current.y() - search_radius));
    const int x1 = static_cast<int>(std::ceil(current.x() + search_radius));
    const int y1 = static_cast<int>(std::ceil(current.y() + search_radius));
    if (x0 < 0 || y0 < 0 || x1 >= gray.cols || y1 >= gray.rows) {
      if (reason) *reason = "marker search disc leaves the image";
      return false;
    }
    const double r2 = search_radius * search_radius;
    values.clear();
    uint8_t darkest = 255;
    for (int y = y0; y <= y1; ++y) {
      const uint8_t* row = gray.ptr<uint8_t>(y);
      for (int x = x0; x <= x1; ++x) {
        const double dx = x - current.x();
        const double dy = y - current.y();
        if (dx * dx + dy * dy > r2) continue;
        values.push_back(row[x]);
        darkest = std::min(darkest, row[x]);
      }
    }
    if (values.size() < 5) {
      if (reason) *reason = "marker search disc is empty";
      return false;
    }
    // The dot covers about 1 / factor^2 (~45 %) of the disc: the 80th percentile is background.
    const size_t k = values.size() * 4 / 5;
    std::nth_element(values.begin(), values.begin() + static_cast<long>(k), values.end());
    const double background = values[k];
    if (background - darkest < params_.min_contrast) {
      if (reason) *reason = "marker has too little contrast";
      return false;
    }
    const double threshold = 0.5 * (background + darkest);
    double sum_w = 0.0;
    double sum_x = 0.0;
    double sum_y = 0.0;
    for (int y = y0; y <= y1; ++y) {
      const uint8_t* row = gray.ptr<uint8_t>(y);
      for (int x = x0; x <= x1; ++x) {
        const double dx = x - current.x();
        const double dy = y - current.y();
        if (dx * dx + dy * dy > r2) continue;
        const double weight = threshold - row[x];
        if (weight <= 0.0) continue;
        sum_w += weight;
        sum_x += weight * x;
        sum_y += weight * y;
      }
    }
    if (sum_w <= 0.0) {
      if (reason) *reason = "marker not found";
      return false;
    }
    current = {sum_x / sum_w, sum_y / sum_w};
  }
  if ((current - predicted).norm() > kMaxShiftInRadii * std::max(radius_px, 1.0) + 1.0) {
    if (reason) *reason = "marker centre far from its predicted position";
    return false;
  }
  *centre = current;
  return true;
}

}  // namespace mono
}  // namespace docking_perception
