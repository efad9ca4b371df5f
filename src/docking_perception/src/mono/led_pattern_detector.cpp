#include "docking_perception/mono/led_pattern_detector.h"

#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>
#include <opencv2/imgproc.hpp>

namespace docking_perception {
namespace mono {
namespace {

// The two arms of a pattern must not look parallel: a degenerate view, or two triples of one line.
constexpr double kMinArmAngleDeg = 15.0;
// A triple's middle blob: off the line by at most 4 % of the triple's length, and at most 0.2 from its
// midpoint along it (perspective moves the projected midpoint). Without
// them (both 1.0) five blobs that were not the pattern gave one confidently wrong IR pose on the stress
// report seeds 640:40 (make ablate, rule led_pattern_tolerances).
constexpr double kCollinearityTolerance = 0.04;
constexpr double kMidpointTolerance = 0.2;

double cross2d(const Eigen::Vector2d& a, const Eigen::Vector2d& b) { return a.x() * b.y() - a.y() * b.x(); }

struct Triple {
  int end_a;
  int middle;
  int end_b;
  double residual;  // normalised collinearity + midpoint residuals
};

// All collinear triples with the middle blob near the midpoint (ends stored unordered: a < b).
std::vector<Triple> collinearTriples(const std::vector<LedBlob>& blobs) {
  const int n = static_cast<int>(blobs.size());
  std::vector<Triple> triples;
  for (int a = 0; a < n; ++a) {
    for (int b = a + 1; b < n; ++b) {
      const Eigen::Vector2d pa = blobs[static_cast<size_t>(a)].centroid;
      const Eigen::Vector2d pb = blobs[static_cast<size_t>(b)].centroid;
      const Eigen::Vector2d ab = pb - pa;
      const double length = ab.norm();
      if (length < 3.0) continue;
      for (int m = 0; m < n; ++m) {
        if (m == a || m == b) continue;
        const Eigen::Vector2d am = blobs[static_cast<size_t>(m)].centroid - pa;
        const double along = am.dot(ab) / (length * length);
        const double off_line = std::abs(cross2d(ab, am)) / length / length;
        const double midpoint_error = std::abs(along - 0.5);
        if (off_line > kCollinearityTolerance || midpoint_error > kMidpointTolerance) continue;
        triples.push_back({a, m, b, off_line / kCollinearityTolerance + midpoint_error / kMidpointTolerance});
      }
    }
  }
  return triples;
}

// The patterns two collinear triples make when they share one end and nothing else (none, or one per shared
// end), their arms not parallel; appended to *candidates. expected_handedness: the sign of cross(arm 2->0,
// arm 2->4) in the image of a front-facing face.
void addPatterns(const std::vector<LedBlob>& blobs, const Triple& t1, const Triple& t2, double expected_handedness,
                 std::vector<LedPatternCandidate>* candidates) {
  const double min_sin = std::sin(kMinArmAngleDeg * M_PI / 180.0);
  // The shared blob must be an end of both triples, and it must be the only shared blob.
  const int ends1[2] = {t1.end_a, t1.end_b};
  const int ends2[2] = {t2.end_a, t2.end_b};
  for (int e1 = 0; e1 < 2; ++e1) {
    for (int e2 = 0; e2 < 2; ++e2) {
      if (ends1[e1] != ends2[e2]) continue;
      const int shared = ends1[e1];
      const int far1 = ends1[1 - e1];
      const int far2 = ends2[1 - e2];
      if (far1 == far2 || t1.middle == t2.middle || t1.middle == far2 || t2.middle == far1) continue;
      const Eigen::Vector2d ps = blobs[static_cast<size_t>(shared)].centroid;
      const Eigen::Vector2d arm1 = blobs[static_cast<size_t>(far1)].centroid - ps;
      const Eigen::Vector2d arm2 = blobs[static_cast<size_t>(far2)].centroid - ps;
      const double sin_angle = cross2d(arm1, arm2) / (arm1.norm() * arm2.norm());
      if (std::abs(sin_angle) < min_sin) continue;
      // Handedness decides which arm is A (2 -> 0) and which is B (2 -> 4).
      const bool first_is_a = sin_angle * expected_handedness > 0.0;
      const Triple& ta = first_is_a ? t1 : t2;
      const Triple& tb = first_is_a ? t2 : t1;
      LedPatternCandidate candidate;
      candidate.blob_indices = {first_is_a ? far1 : far2, ta.middle, shared, tb.middle, first_is_a ? far2 : far1};
      for (int k = 0; k < kMarkerCount; ++k) {
        candidate.pixels[static_cast<size_t>(k)] =
            blobs[static_cast<size_t>(candidate.blob_indices[static_cast<size_t>(k)])].centroid;
      }
      candidate.score = ta.residual + tb.residual;
      candidates->push_back(candidate);
    }
  }
}

}  // namespace

LedPatternDetector::LedPatternDetector(const MarkerPoints& markers, const LedDetectorParams& params)
    : params_(params) {
  // Image handedness of a face seen from the front, from the camera's view of the model: in the
  // camera (x right, y down, z forward) a face whose normal n (+x of `target`) points at the camera
  // has n_z < 0, and the image cross product of two arms has the sign of -(arm_a x arm_b) . n.
  const Eigen::Vector3d arm_a = markers[0] - markers[2];
  const Eigen::Vector3d arm_b = markers[4] - markers[2];
  expected_handedness_ = -arm_a.cross(arm_b).dot(Eigen::Vector3d::UnitX()) > 0.0 ? 1.0 : -1.0;
}

namespace {

struct ComponentShape {
  double elongation = 1.0;
  double streak_sigma_px = 0.0;
};

// The shape of one labelled component from its second moments. Elongation: the ratio of the principal
// axes (square roots of the eigenvalues); a round LED spot gives ~1, an LED merged with a reflection
// beside it 2 or more. Streak: sqrt(largest - smallest eigenvalue), what a motion streak of length L adds
// along its direction (L / sqrt(12), the sigma of a box of that length); ~0 for a round spot.
ComponentShape componentShape(const cv::Mat& labels, int label, const cv::Rect& box) {
  double n = 0.0, sx = 0.0, sy = 0.0, sxx = 0.0, syy = 0.0, sxy = 0.0;
  for (int y = box.y; y < box.y + box.height; ++y) {
    const int* row = labels.ptr<int>(y);
    for (int x = box.x; x < box.x + box.width; ++x) {
      if (row[x] != label) continue;
      n += 1.0;
      sx += x;
      sy += y;
      sxx += static_cast<double>(x) * x;
      syy += static_cast<double>(y) * y;
      sxy += static_cast<double>(x) * y;
    }
  }
  if (n < 2.0) return ComponentShape();
  // Pixel extent (1/12 per axis) keeps a 1-2 pixel blob from reading as a line.
  const double cxx = sxx / n - (sx / n) * (sx / n) + 1.0 / 12.0;
  const double cyy = syy / n - (sy / n) * (sy / n) + 1.0 / 12.0;
  const double cxy = sxy / n - (sx / n) * (sy / n);
  const double mean = 0.5 * (cxx + cyy);
  const double spread = std::sqrt(0.25 * (cxx - cyy) * (cxx - cyy) + cxy * cxy);
  ComponentShape shape;
  shape.elongation = std::sqrt((mean + spread) / std::max(1e-9, mean - spread));
  shape.streak_sigma_px = std::sqrt(2.0 * spread);
  return shape;
}

// The blob of component `label` of `view` (the search region, at `roi_corner` in the image): its sub-pixel
// centre, intensity-weighted over its box grown by 2 px above the level of that box's border (the skirt
// below the threshold keeps the precision a saturated, flat-topped core alone would lose), its peak and its
// shape. False when it is no brighter than its border.
bool measureBlob(const cv::Mat& view, const cv::Mat& labels, const cv::Mat& stats, int label, cv::Point roi_corner,
                 LedBlob* blob) {
  const int w = stats.at<int>(label, cv::CC_STAT_WIDTH);
  const int h = stats.at<int>(label, cv::CC_STAT_HEIGHT);
  const cv::Rect component(stats.at<int>(label, cv::CC_STAT_LEFT), stats.at<int>(label, cv::CC_STAT_TOP), w, h);
  const cv::Rect box = cv::Rect(component.x - 2, component.y - 2, w + 4, h + 4) & cv::Rect(0, 0, view.cols, view.rows);
  double border_sum = 0.0;
  int border_count = 0;
  for (int y = box.y; y < box.y + box.height; ++y) {
    const uint8_t* row = view.ptr<uint8_t>(y);
    for (int x = box.x; x < box.x + box.width; ++x) {
      if (y != box.y && y != box.y + box.height - 1 && x != box.x && x != box.x + box.width - 1) continue;
      border_sum += row[x];
      ++border_count;
    }
  }
  const double background = border_count > 0 ? border_sum / border_count : 0.0;
  double sum_w = 0.0, sum_x = 0.0, sum_y = 0.0, peak = 0.0;
  for (int y = box.y; y < box.y + box.height; ++y) {
    const uint8_t* row = view.ptr<uint8_t>(y);
    for (int x = box.x; x < box.x + box.width; ++x) {
      const double weight = static_cast<double>(row[x]) - background;
      if (weight <= 0.0) continue;
      sum_w += weight;
      sum_x += weight * x;
      sum_y += weight * y;
      peak = std::max(peak, static_cast<double>(row[x]));
    }
  }
  if (sum_w <= 0.0) return false;
  const ComponentShape shape = componentShape(labels, label, component);
  blob->elongation = shape.elongation;
  blob->streak_sigma_px = shape.streak_sigma_px;
  blob->centroid = {sum_x / sum_w + roi_corner.x, sum_y / sum_w + roi_corner.y};
  blob->area_px = stats.at<int>(label, cv::CC_STAT_AREA);
  blob->peak = peak;
  return true;
}

}  // namespace

double medianStreakSigma(const std::vector<LedBlob>& blobs, const LedPatternCandidate& candidate) {
  std::vector<double> streaks;
  for (const int index : candidate.blob_indices) {
    if (index >= 0 && static_cast<size_t>(index) < blobs.size()) {
      streaks.push_back(blobs[static_cast<size_t>(index)].streak_sigma_px);
    }
  }
  if (streaks.empty()) return 0.0;
  std::nth_element(streaks.begin(), streaks.begin() + static_cast<long>(streaks.size() / 2), streaks.end());
  return streaks[streaks.size() / 2];
}

std::vector<LedBlob> LedPatternDetector::detectBlobs(const cv::Mat& gray, const cv::Rect& roi_in) const {
  std::vector<LedBlob> blobs;
  if (gray.empty() || gray.type() != CV_8UC1) return blobs;
  const cv::Rect full(0, 0, gray.cols, gray.rows);
  const cv::Rect roi = roi_in.area() > 0 ? (roi_in & full) : full;
  if (roi.area() <= 0) return blobs;
  const cv::Mat view = gray(roi);
  cv::Mat mask;
  cv::threshold(view, mask, params_.threshold - 1, 255, cv::THRESH_BINARY);
  cv::Mat labels;
  cv::Mat stats;
  cv::Mat centroids;
  const int count = cv::connectedComponentsWithStats(mask, labels, stats, centroids, 8, CV_32S);
  for (int label = 1; label < count; ++label) {
    LedBlob blob;
    if (measureBlob(view, labels, stats, label, roi.tl(), &blob)) blobs.push_back(blob);
  }
  // Keep the largest blobs: LEDs are among the brightest, biggest spots, and the search is O(n^3).
  constexpr size_t kMaxBlobs = 16;
  std::sort(blobs.begin(), blobs.end(), [](const LedBlob& a, const LedBlob& b) { return a.area_px > b.area_px; });
  if (blobs.size() > kMaxBlobs) blobs.resize(kMaxBlobs);
  return blobs;
}
std::vector<LedPatternCandidate> LedPatternDetector::identifyPattern(const std::vector<LedBlob>& blobs,
                                                                     std::string* reason) const {
  std::vector<LedPatternCandidate> candidates;
  const int n = static_cast<int>(blobs.size());
  if (n < kMarkerCount) {
    if (reason) *reason = "found " + std::to_string(n) + " LED blobs, the pattern needs 5";
    return candidates;
  }
  const std::vector<Triple> triples = collinearTriples(blobs);
  for (size_t i = 0; i < triples.size(); ++i) {
    for (size_t j = i + 1; j < triples.size(); ++j) {
      addPatterns(blobs, triples[i], triples[j], expected_handedness_, &candidates);
    }
  }
  std::sort(candidates.begin(), candidates.end(),
            [](const LedPatternCandidate& a, const LedPatternCandidate& b) { return a.score < b.score; });
  if (candidates.empty() && reason) {
    *reason = "no 5-point LED pattern among " + std::to_string(n) + " blobs (" + std::to_string(triples.size()) +
              " collinear triples)";
  }
  return candidates;
}

}  // namespace mono
}  // namespace docking_perception
