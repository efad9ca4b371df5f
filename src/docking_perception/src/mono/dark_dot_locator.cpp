#include "docking_perception/mono/dark_dot_locator.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <utility>
#include <vector>

#include <opencv2/imgproc.hpp>

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

namespace {

// A radius is looked for on the pyramid level where it is at least this many pixels (and under twice it).
constexpr double kMinLevelRadiusPx = 2.0;
// The circle sampled around a candidate: between the dot's edge (1 radius) and the white ring's outer edge
// (>= 1.6 radii, target_print's ring_outer_factor).
constexpr double kRingRadiusInDotRadii = 1.4;
// A candidate's third-darkest circle sample is at least this much brighter than its centre (8-bit levels:
// several times the noise left after the level's smoothing).
constexpr int kMinStrength = 10;

// True when p[0] is the darkest of its 3x3 neighbourhood in an image of row `step`: strictly darker than the
// neighbours after it (right, below), at most as dark as those before it, so a flat patch gives no minimum
// and a two-pixel minimum one.
bool localMinimum(const uint8_t* p, size_t step) {
  const uint8_t c = p[0];
  const uint8_t* up = p - step;
  const uint8_t* down = p + step;
  return c < p[1] && c < down[0] && c <= p[-1] && c <= up[0] && c < down[1] && c < down[-1] && c <= up[-1] &&
         c <= up[1];
}

// The 8 samples of the circle around a candidate, as offsets in a level image of row `step`.
std::array<long, 8> ringOffsets(double ring_px, size_t step) {
  std::array<long, 8> offsets{};
  for (int k = 0; k < 8; ++k) {
    const long dx = std::lround(ring_px * std::cos(k * M_PI / 4.0));
    const long dy = std::lround(ring_px * std::sin(k * M_PI / 4.0));
    offsets[static_cast<size_t>(k)] = dy * static_cast<long>(step) + dx;
  }
  return offsets;
}

// How much brighter than the centre p[0] the third-darkest circle sample is; 0 as soon as three samples are
// less than kMinStrength brighter (most local minima of the noise are refused after three or four samples).
int ringStrength(const uint8_t* p, const std::array<long, 8>& offsets) {
  const int centre = p[0];
  int dark = 0;
  int a = 256, b = 256, c = 256;  // the three smallest samples so far, a <= b <= c
  for (const long offset : offsets) {
    const int x = p[offset];
    if (x < centre + kMinStrength && ++dark > 2) return 0;
    if (x < c) {
      c = x < b ? b : x;
      if (x < b) {
        b = x < a ? a : x;
        if (x < a) a = x;
      }
    }
  }
  return c - centre;
}

}  // namespace

DarkDotFinder::DarkDotFinder(std::vector<double> radii_px) : radii_px_(std::move(radii_px)) {
  // Each radius on the pyramid level where it is 2-4 px.
  for (size_t r = 0; r < radii_px_.size(); ++r) {
    size_t level = 0;
    while (radii_px_[r] / (1 << (level + 1)) >= kMinLevelRadiusPx) ++level;
    if (radii_of_level_.size() <= level) radii_of_level_.resize(level + 1);
    radii_of_level_[level].push_back(r);
  }
}

void DarkDotFinder::findOnLevel(const cv::Mat& level, int level_index, const std::vector<size_t>& radii,
                                std::vector<std::vector<Candidate>>* found) const {
  const double scale = static_cast<double>(1 << level_index);
  const size_t step = level.step[0];
  std::vector<std::array<long, 8>> offsets;
  int border = 1;
  for (const size_t r : radii) {
    const double ring = kRingRadiusInDotRadii * radii_px_[r] / scale;
    offsets.push_back(ringOffsets(ring, step));
    border = std::max(border, static_cast<int>(std::ceil(ring)) + 1);
  }
  for (int y = border; y < level.rows - border; ++y) {
    const uint8_t* row = level.ptr<uint8_t>(y);
    for (int x = border; x < level.cols - border; ++x) {
      const uint8_t* p = row + x;
      if (!localMinimum(p, step)) continue;
      for (size_t i = 0; i < radii.size(); ++i) {
        const int strength = ringStrength(p, offsets[i]);
        if (strength < kMinStrength) continue;
        // A level pixel covers scale x scale image pixels: its centre in the image.
        const Eigen::Vector2d centre((x + 0.5) * scale - 0.5, (y + 0.5) * scale - 0.5);
        (*found)[radii[i]].push_back({centre, radii_px_[radii[i]], static_cast<double>(strength)});
      }
    }
  }
}

std::vector<std::vector<LedBlob>> DarkDotFinder::find(const cv::Mat& gray, size_t max_per_radius) const {
  std::vector<std::vector<LedBlob>> found;
  if (gray.empty() || gray.type() != CV_8UC1) return found;
  // The levels: the image smoothed 3x3 (the noise), then halved.
  std::vector<std::vector<Candidate>> candidates(radii_px_.size());
  cv::Mat level;
  cv::blur(gray, level, cv::Size(3, 3));
  for (size_t l = 0; l < radii_of_level_.size(); ++l) {
    if (l > 0) cv::pyrDown(level, level);
    if (!radii_of_level_[l].empty()) findOnLevel(level, static_cast<int>(l), radii_of_level_[l], &candidates);
  }
  for (std::vector<Candidate>& at_radius : candidates) {
    found.push_back(strongestDots(gray, std::move(at_radius), max_per_radius));
  }
  return found;
}

std::vector<LedBlob> DarkDotFinder::strongestDots(const cv::Mat& gray, std::vector<Candidate> candidates,
                                                  size_t max_dots) const {
  std::sort(candidates.begin(), candidates.end(),
            [](const Candidate& a, const Candidate& b) { return a.strength > b.strength; });
  // One per place: a candidate within the radius of a stronger one is the same dot.
  std::vector<LedBlob> dots;
  for (const Candidate& c : candidates) {
    if (dots.size() >= max_dots) break;
    const bool taken = std::any_of(dots.begin(), dots.end(),
                                   [&](const LedBlob& d) { return (d.centroid - c.centre).norm() < c.radius_px; });
    if (taken) continue;
    LedBlob dot;
    // The centre to a fraction of a pixel where the locator can (the pattern's tolerances need it at the
    // coarse levels); else the level's pixel.
    if (!locator_.locate(gray, c.centre, c.radius_px, &dot.centroid, nullptr)) dot.centroid = c.centre;
    dot.area_px = M_PI * c.radius_px * c.radius_px;
    dot.peak = c.strength;
    dots.push_back(dot);
  }
  return dots;
}

}  // namespace mono
}  // namespace docking_perception
