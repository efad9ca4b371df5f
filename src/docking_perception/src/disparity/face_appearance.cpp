#include "docking_perception/disparity/face_appearance.h"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <stdexcept>
#include <vector>

#include <opencv2/imgproc.hpp>

#include "number_text.h"

namespace docking_perception {
namespace disparity {

// Where the face and its search margin lie in the image, at full resolution.
struct AppearanceSearchLayout {
  cv::Point2d centre_px;    // the detected port
  double face_width_px = 0, face_height_px = 0;
  double radius_px = 0;     // search margin across; half of it up and down
  cv::Rect face_rect;       // the expected face (clipped to the image)
  cv::Rect region;          // face + margin, clipped to the image
};

namespace {

// Image and print are reduced so the face is at most this wide: its five rings and the port ring still
// resolve, and the search stays cheap (a constant of the method).
constexpr double kWorkingWidthPx = 24.0;
// The print is kept at this width (area-averaged once), wider than the working width, so reducing from
// here stays an average.
constexpr int kPrintWorkingWidthPx = static_cast<int>(kMaxAppearanceWorkingWidthPx);
// Grey at or above this is saturated (8-bit images: the sensor's ceiling less its noise).
constexpr int kSaturatedLevelDn = 250;
// The print is slid this far either side of the detected port: a turned target's footprint fit puts the port
// up to 0.23 m aside (rendered far scenes);
constexpr double kSearchRadiusM = 0.25;
constexpr double kVerticalSearchFraction = 0.5;  // of kSearchRadiusM, up and down
// The face's depth replaces the footprint fit's when they differ by more than this many of the estimate's
// depth sigmas (the fit's port jumps ~0.1 m between yaw basins on a turned target, seed 7605 at 2.2 m).
constexpr double kDepthDisagreementSigmas = 2.0;
// Smallest print the correlation is meaningful on (pixels, at the working scale).
constexpr int kMinTemplateWidthPx = 8;
constexpr int kMinTemplateHeightPx = 6;

double saturatedFraction(const cv::Mat& grey, int level) {
  if (grey.empty()) return 0.0;
  cv::Mat saturated;
  cv::compare(grey, level, saturated, cv::CMP_GE);
  return static_cast<double>(cv::countNonZero(saturated)) / static_cast<double>(grey.total());
}


AppearanceSearchLayout layoutOf(const cv::Size& image, const StereoGeometry& g, const Eigen::Vector3d& port,
                      double face_width_m, double face_height_m, double radius_m) {
  AppearanceSearchLayout layout;
  const double z = port.z();
  layout.centre_px = {g.cx_px + g.focal_px * port.x() / z, g.cy_px + g.focal_px * port.y() / z};
  layout.face_width_px = g.focal_px * face_width_m / z;
  layout.face_height_px = g.focal_px * face_height_m / z;
  layout.radius_px = g.focal_px * radius_m / z;
  const cv::Rect whole(0, 0, image.width, image.height);
  const auto rectAround = [&](double half_w, double half_h) {
    const int x0 = static_cast<int>(std::floor(layout.centre_px.x - half_w));
    const int y0 = static_cast<int>(std::floor(layout.centre_px.y - half_h));
    const int x1 = static_cast<int>(std::ceil(layout.centre_px.x + half_w));
    const int y1 = static_cast<int>(std::ceil(layout.centre_px.y + half_h));
    return cv::Rect(x0, y0, x1 - x0, y1 - y0) & whole;
  };
  layout.face_rect = rectAround(layout.face_width_px / 2, layout.face_height_px / 2);
  // The detector's port errs across the line of sight (a turned target's footprint), hardly in height (the
  // face layer's rows): half the margin vertically keeps the search small.
  layout.region = rectAround(layout.face_width_px / 2 + layout.radius_px,
                             layout.face_height_px / 2 + kVerticalSearchFraction * layout.radius_px);
  return layout;
}

// The print reduced to `size`, zero mean and unit norm: its dot product with an image patch is then the
// patch's normalised correlation times the patch's own norm.
cv::Mat normalisedTemplate(const cv::Mat& print, cv::Size size) {
  cv::Mat reduced;
  cv::resize(print, reduced, size, 0, 0, cv::INTER_AREA);
  reduced -= cv::mean(reduced)[0];
  const double norm = cv::norm(reduced);
  if (norm > 0.0) reduced /= norm;
  return reduced;
}

// `image` reduced to `size` by averaging each output pixel's footprint (whole input pixels, read from an
// integral image): cv::resize's area mode costs ~100 instructions a pixel at non-integer ratios, as much
// as the whole search.
cv::Mat areaReduced(const cv::Mat& image, cv::Size size) {
  cv::Mat integral;
  cv::integral(image, integral, CV_32S);
  cv::Mat reduced(size, CV_32F);
  std::vector<int> column_edges(static_cast<std::size_t>(size.width) + 1);
  for (int c = 0; c <= size.width; ++c) column_edges[static_cast<std::size_t>(c)] = c * image.cols / size.width;
  for (int r = 0; r < size.height; ++r) {
    const int y0 = r * image.rows / size.height, y1 = std::max(y0 + 1, (r + 1) * image.rows / size.height);
    const int* top = integral.ptr<int>(y0);
    const int* bottom = integral.ptr<int>(y1);
    float* out = reduced.ptr<float>(r);
    for (int c = 0; c < size.width; ++c) {
      const int x0 = column_edges[static_cast<std::size_t>(c)];
      const int x1 = std::max(x0 + 1, column_edges[static_cast<std::size_t>(c) + 1]);
      out[c] = static_cast<float>(bottom[x1] - bottom[x0] - top[x1] + top[x0]) / static_cast<float>((x1 - x0) * (y1 - y0));
    }
  }
  return reduced;
}

struct Match {
  double score = -1.0;
  cv::Point at;  // top-left of the template in the region
};

// Normalised correlation of the template at one place of the region (sums: the region's integral images).
double correlationAt(const cv::Mat& region, const cv::Mat& sum, const cv::Mat& square_sum, const cv::Mat& tmpl,
                     int x, int y) {
  double dot = 0.0;
  for (int r = 0; r < tmpl.rows; ++r) {
    const float* t = tmpl.ptr<float>(r);
    const float* i = region.ptr<float>(y + r) + x;
    // Eight independent sums: a single running sum is one long dependency chain the compiler may not
    // reorder (float addition), these it packs into vector instructions.
    float lanes[8] = {};
    int c = 0;
    for (; c + 8 <= tmpl.cols; c += 8) {
      for (int k = 0; k < 8; ++k) lanes[k] += t[c + k] * i[c + k];
    }
    float row = ((lanes[0] + lanes[1]) + (lanes[2] + lanes[3])) + ((lanes[4] + lanes[5]) + (lanes[6] + lanes[7]));
    for (; c < tmpl.cols; ++c) row += t[c] * i[c];
    dot += row;
  }
  const auto boxOf = [&](const cv::Mat& integral) {
    return integral.at<double>(y + tmpl.rows, x + tmpl.cols) - integral.at<double>(y, x + tmpl.cols) -
           integral.at<double>(y + tmpl.rows, x) + integral.at<double>(y, x);
  };
  const double n = static_cast<double>(tmpl.total());
  const double s = boxOf(sum);
  const double variance_sum = boxOf(square_sum) - s * s / n;  // sum of (I - mean)^2 over the patch
  return variance_sum > 1e-6 ? dot / std::sqrt(variance_sum) : 0.0;
}

// The best place of the template in the region: every second place first, then the 3x3 around the best.
// The print's correlation peak is wider than two pixels at the working scale (blur, area reduction).
Match bestMatch(const cv::Mat& region, const cv::Mat& sum, const cv::Mat& square_sum, const cv::Mat& tmpl) {
  Match best;
  const int max_x = region.cols - tmpl.cols, max_y = region.rows - tmpl.rows;
  for (int y = 0; y <= max_y; y += 2) {
    for (int x = 0; x <= max_x; x += 2) {
      const double score = correlationAt(region, sum, square_sum, tmpl, x, y);
      if (score > best.score) best = {score, {x, y}};
    }
  }
  const cv::Point coarse = best.at;
  for (int y = std::max(0, coarse.y - 1); y <= std::min(max_y, coarse.y + 1); ++y) {
    for (int x = std::max(0, coarse.x - 1); x <= std::min(max_x, coarse.x + 1); ++x) {
      if ((x - coarse.x) % 2 == 0 && (y - coarse.y) % 2 == 0) continue;  // visited
      const double score = correlationAt(region, sum, square_sum, tmpl, x, y);
      if (score > best.score) best = {score, {x, y}};
    }
  }
  return best;
}

}  // namespace

const std::vector<double>& appearanceSqueezes() {
  static const std::vector<double> squeezes = [] {
    std::vector<double> values;
    for (double yaw_deg : {0.0, 30.0, 45.0, 60.0}) values.push_back(std::cos(yaw_deg * M_PI / 180.0));
    return values;
  }();
  return squeezes;
}

const char* appearanceVerdictName(AppearanceVerdict verdict) {
  switch (verdict) {
    case AppearanceVerdict::kNotChecked: return "not_checked";
    case AppearanceVerdict::kLooksLikeTarget: return "looks_like_target";
    case AppearanceVerdict::kNotTheTarget: return "not_the_target";
    case AppearanceVerdict::kGlare: return "glare";
    case AppearanceVerdict::kTooDark: return "too_dark";
    case AppearanceVerdict::kOutsideImage: return "outside_image";
  }
  return "unknown";
}

bool isUnjudged(AppearanceVerdict verdict) {
  return verdict == AppearanceVerdict::kGlare || verdict == AppearanceVerdict::kTooDark ||
         verdict == AppearanceVerdict::kOutsideImage;
}

FaceAppearanceCheck::FaceAppearanceCheck(const cv::Mat& print_grey, double face_width_m, double face_height_m)
    : face_width_m_(face_width_m), face_height_m_(face_height_m) {
  if (print_grey.empty() || print_grey.type() != CV_8UC1)
    throw std::invalid_argument("face print must be a non-empty 8-bit grey image");
  if (!(face_width_m > 0.0) || !(face_height_m > 0.0))
    throw std::invalid_argument("face size must be positive (got " + formatNumber(face_width_m) + " x " +
                                formatNumber(face_height_m) + " m)");
  const int height = std::max(1, static_cast<int>(std::lround(kPrintWorkingWidthPx * face_height_m / face_width_m)));
  cv::Mat reduced;
  cv::resize(print_grey, reduced, cv::Size(kPrintWorkingWidthPx, height), 0, 0, cv::INTER_AREA);
  reduced.convertTo(print_, CV_32F);
}

cv::Mat FaceAppearanceCheck::printOfSize(cv::Size size) const {
  const std::uint64_t key = (static_cast<std::uint64_t>(size.width) << 32) | static_cast<std::uint32_t>(size.height);
  std::lock_guard<std::mutex> lock(reduced_prints_mutex_);
  auto found = reduced_prints_.find(key);
  if (found == reduced_prints_.end()) found = reduced_prints_.emplace(key, normalisedTemplate(print_, size)).first;
  return found->second;
}

namespace {

// Whether the face can be judged where `layout` puts it: mostly inside the image, not saturated by glare, not
// too dark. Otherwise `result` says which, and why.
bool judgeable(const cv::Mat& left_rect, const AppearanceSearchLayout& layout, const FaceAppearanceParams& p,
               AppearanceResult* result) {
  if (layout.face_rect.area() < 0.5 * layout.face_width_px * layout.face_height_px) {
    result->verdict = AppearanceVerdict::kOutsideImage;
    result->reason = "appearance not checked: the face is mostly outside the image";
    return false;
  }
  result->saturated_fraction = saturatedFraction(left_rect(layout.face_rect), kSaturatedLevelDn);
  result->mean_dn = cv::mean(left_rect(layout.region))[0];
  if (result->saturated_fraction > p.max_saturated_fraction) {
    result->verdict = AppearanceVerdict::kGlare;
    result->reason = "appearance not judged: " + formatNumber(100.0 * result->saturated_fraction) +
                     " % of the face saturated (glare)";
    return false;
  }
  if (result->mean_dn < p.min_mean_dn) {
    result->verdict = AppearanceVerdict::kTooDark;
    result->reason = "appearance not judged: mean grey " + formatNumber(result->mean_dn) + " < " +
                     formatNumber(p.min_mean_dn) + " (too dark)";
    return false;
  }
  return true;
}

}  // namespace

AppearanceResult FaceAppearanceCheck::check(const cv::Mat& left_rect, const StereoGeometry& geometry,
                                            const Eigen::Vector3d& port_m, const FaceAppearanceParams& p) const {
  AppearanceResult result;
  if (!ready() || left_rect.empty() || left_rect.type() != CV_8UC1 || !(port_m.z() > 0.0) ||
      !port_m.allFinite() || !(geometry.focal_px > 0.0)) {
    result.reason = "appearance not checked: no print, no grey image or no port in front of the camera";
    return result;
  }
  const AppearanceSearchLayout layout =
      layoutOf(left_rect.size(), geometry, port_m, face_width_m_, face_height_m_, kSearchRadiusM);
  if (judgeable(left_rect, layout, p, &result)) matchPrint(left_rect, layout, p, &result);
  return result;
}

void FaceAppearanceCheck::matchPrint(const cv::Mat& left_rect, const AppearanceSearchLayout& layout,
                                     const FaceAppearanceParams& p, AppearanceResult* result) const {
  // Work at a scale where the face is at most kWorkingWidthPx wide (never enlarge).
  const double scale = std::min(1.0, kWorkingWidthPx / layout.face_width_px);
  cv::Mat region_f;
  if (scale < 1.0) {
    const cv::Size reduced(std::max(1, static_cast<int>(std::lround(layout.region.width * scale))),
                           std::max(1, static_cast<int>(std::lround(layout.region.height * scale))));
    region_f = areaReduced(left_rect(layout.region), reduced);
  } else {
    left_rect(layout.region).convertTo(region_f, CV_32F);
  }
  cv::Mat sum, square_sum;
  cv::integral(region_f, sum, square_sum, CV_64F, CV_64F);
  const double sx = static_cast<double>(region_f.cols) / layout.region.width;
  const double sy = static_cast<double>(region_f.rows) / layout.region.height;

  result->verdict = AppearanceVerdict::kOutsideImage;
  result->score = -1.0;
  bool any_fit = false;
  const int template_height = static_cast<int>(std::lround(layout.face_height_px * sy));
  for (double squeeze : appearanceSqueezes()) {
    const int template_width = static_cast<int>(std::lround(layout.face_width_px * sx * squeeze));
    if (template_width < kMinTemplateWidthPx || template_height < kMinTemplateHeightPx) continue;
    if (template_width > region_f.cols || template_height > region_f.rows) continue;
    const cv::Mat print = printOfSize(cv::Size(template_width, template_height));
    const Match match = bestMatch(region_f, sum, square_sum, print);
    any_fit = true;
    if (match.score > result->score) {
      result->score = match.score;
      result->squeeze = squeeze;
      result->matched_centre_px = {layout.region.x + (match.at.x + template_width / 2.0) / sx,
                                   layout.region.y + (match.at.y + template_height / 2.0) / sy};
      result->matched_size_px = {template_width / sx, template_height / sy};
    }
  }
  if (!any_fit) {
    result->verdict = AppearanceVerdict::kOutsideImage;
    result->score = 0.0;
    result->reason = "appearance not checked: the face is too small or the image around it too narrow";
    return;
  }
  const bool match = result->score >= p.min_score;
  result->verdict = match ? AppearanceVerdict::kLooksLikeTarget : AppearanceVerdict::kNotTheTarget;
  result->reason = std::string(match ? "looks like the target's face" : "does not look like the target's face") +
                   ": print match " + formatNumber(result->score) + (match ? " >= " : " < ") +
                   "appearance_min_score " + formatNumber(p.min_score);
}

namespace {

// Median of the valid (> 0, finite) disparities over the middle half of the matched print, or 0 when fewer
// than a quarter of them are valid.
double faceDisparity(const cv::Mat& disparity, const AppearanceResult& match) {
  if (disparity.empty() || disparity.type() != CV_32FC1) return 0.0;
  const cv::Rect middle(static_cast<int>(std::lround(match.matched_centre_px.x - match.matched_size_px.width / 4.0)),
                        static_cast<int>(std::lround(match.matched_centre_px.y - match.matched_size_px.height / 4.0)),
                        std::max(1, static_cast<int>(std::lround(match.matched_size_px.width / 2.0))),
                        std::max(1, static_cast<int>(std::lround(match.matched_size_px.height / 2.0))));
  const cv::Rect inside = middle & cv::Rect(0, 0, disparity.cols, disparity.rows);
  std::vector<float> values;
  values.reserve(static_cast<std::size_t>(inside.area()));
  for (int r = inside.y; r < inside.y + inside.height; ++r) {
    const float* row = disparity.ptr<float>(r);
    for (int c = inside.x; c < inside.x + inside.width; ++c) {
      if (std::isfinite(row[c]) && row[c] > 0.0f) values.push_back(row[c]);
    }
  }
  if (values.empty() || 4 * values.size() < static_cast<std::size_t>(middle.area())) return 0.0;
  const auto mid = values.begin() + static_cast<std::ptrdiff_t>(values.size() / 2);
  std::nth_element(values.begin(), mid, values.end());
  return *mid;
}

}  // namespace

AppearanceResult confirmByAppearance(const FaceAppearanceCheck& check, const cv::Mat& left_rect,
                                     const cv::Mat& disparity, const StereoGeometry& geometry,
                                     const FaceAppearanceParams& params, Detection* detection) {
  AppearanceResult result;
  if (!detection->found) {
    result.reason = "appearance not checked: no target found";
    return result;
  }
  result = check.check(left_rect, geometry, detection->position_m, params);
  detection->appearance_judged = !isUnjudged(result.verdict);
  detection->appearance_score = detection->appearance_judged ? result.score : 0.0;
  if (result.verdict == AppearanceVerdict::kLooksLikeTarget && params.refine_port) {
    // The face's own depth replaces the footprint fit's only when the two disagree: farther than a few
    // metres the fit, over the whole blob, is the steadier (4-6 m rendered: 13-16 against 37-56 mm off).
    const double face_disparity_px = faceDisparity(disparity, result);
    const double face_z = face_disparity_px > 0.0 ? geometry.focal_px * geometry.baseline_m / face_disparity_px : 0.0;
    const double depth_sigma_m = std::sqrt(std::max(0.0, detection->covariance_m2(2, 2)));
    const bool take_face_depth =
        face_z > 0.0 && std::abs(face_z - detection->position_m.z()) > kDepthDisagreementSigmas * depth_sigma_m;
    const double z = take_face_depth ? face_z : detection->position_m.z();
    if (take_face_depth) detection->disparity_px = face_disparity_px;
    detection->position_m.x() = (result.matched_centre_px.x - geometry.cx_px) * z / geometry.focal_px;
    detection->position_m.y() = (result.matched_centre_px.y - geometry.cy_px) * z / geometry.focal_px;
    detection->position_m.z() = z;
    detection->range_m = detection->position_m.norm();
    detection->centre_px = result.matched_centre_px;
  }
  if (result.verdict == AppearanceVerdict::kNotTheTarget) {
    detection->found = false;
    detection->outcome = AppearanceOutcome::kMismatch;
    detection->reason = "not the target: " + result.reason;
  }
  if (result.verdict == AppearanceVerdict::kGlare) {
    detection->found = false;
    detection->outcome = AppearanceOutcome::kGlare;
    detection->reason = "not confirmed: " + result.reason +
                        "; glare hides part of the mockup, the port cannot be placed";
  }
  return result;
}

}  // namespace disparity
}  // namespace docking_perception
