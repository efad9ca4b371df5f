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
// The search disc is 1.5 dot radii: it stays inside the white ring target_print draws around each dot
// (ring_outer_factor >= 1.6). A dot is at least 25 levels (8-bit) darker than that background
// (paper_5point only, not shipped).
constexpr double kSearchRadiusInDotRadii = 1.5;
constexpr double kMinDotContrast = 25.0;

// The pixels of the disc of `radius` around `centre` (in the image: checked by the caller).
template <typename Visit>
void forDisc(const cv::Mat& gray, const Eigen::Vector2d& centre, double radius, const cv::Rect& box, Visit&& visit) {
  const double r2 = radius * radius;
  for (int y = box.y; y < box.y + box.height; ++y) {
    const uint8_t* row = gray.ptr<uint8_t>(y);
    for (int x = box.x; x < box.x + box.width; ++x) {
      const double dx = x - centre.x();
      const double dy = y - centre.y();
      if (dx * dx + dy * dy <= r2) visit(x, y, row[x]);
    }
  }
}

// One step: the centroid of the disc's pixels darker than the midpoint of its background (80th percentile)
// and its darkest pixel, each weighted by how much darker, becomes *current. The reason when it cannot.
const char* recentre(const cv::Mat& gray, double search_radius, double min_contrast, Eigen::Vector2d* current) {
  const int x0 = static_cast<int>(std::floor(current->x() - search_radius));
  const int y0 = static_cast<int>(std::floor(current->y() - search_radius));
  const int x1 = static_cast<int>(std::ceil(current->x() + search_radius));
  const int y1 = static_cast<int>(std::ceil(current->y() + search_radius));
  if (x0 < 0 || y0 < 0 || x1 >= gray.cols || y1 >= gray.rows) return "marker search disc leaves the image";
  const cv::Rect box(x0, y0, x1 - x0 + 1, y1 - y0 + 1);
  std::vector<uint8_t> values;
  uint8_t darkest = 255;
  forDisc(gray, *current, search_radius, box, [&](int, int, uint8_t value) {
    values.push_back(value);
    darkest = std::min(darkest, value);
  });
  if (values.size() < 5) return "marker search disc is empty";
  // The dot covers about 1 / factor^2 (~45 %) of the disc: the 80th percentile is background.
  const size_t k = values.size() * 4 / 5;
  std::nth_element(values.begin(), values.begin() + static_cast<long>(k), values.end());
  const double background = values[k];
  if (background - darkest < min_contrast) return "marker has too little contrast";
  const double threshold = 0.5 * (background + darkest);
  double sum_w = 0.0;
  double sum_x = 0.0;
  double sum_y = 0.0;
  forDisc(gray, *current, search_radius, box, [&](int x, int y, uint8_t value) {
    const double weight = threshold - value;
    if (weight <= 0.0) return;
    sum_w += weight;
    sum_x += weight * x;
    sum_y += weight * y;
  });
  if (sum_w <= 0.0) return "marker not found";
  *current = {sum_x / sum_w, sum_y / sum_w};
  return nullptr;
}

}  // namespace

bool DarkDotLocator::locate(const cv::Mat& gray, const Eigen::Vector2d& predicted, double radius_px,
                            Eigen::Vector2d* centre, std::string* reason) const {
  if (gray.empty() || gray.type() != CV_8UC1) {
    if (reason) *reason = "image is not 8-bit gray";
    return false;
  }
  const double search_radius = std::max(kMinSearchRadiusPx, kSearchRadiusInDotRadii * radius_px);
  Eigen::Vector2d current = predicted;
  for (int iteration = 0; iteration < 2; ++iteration) {
    const char* problem = recentre(gray, search_radius, kMinDotContrast, &current);
    if (problem != nullptr) {
      if (reason) *reason = problem;
      return false;
    }
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
