#include "docking_perception/disparity/disparity_detector.h"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <sstream>
#include <stdexcept>

#include <opencv2/imgproc.hpp>

namespace docking_perception {
namespace disparity {
namespace {

// Sub-pixel resolution of the closest-disparity histogram: OpenCV's matchers give 1/16 px.
constexpr double kHistogramBinsPerPx = 16.0;
// How many too-small near objects the search may look behind before it gives up.
constexpr int kMaxNearObjectsSkipped = 5;

std::string joinErrors(const std::vector<std::string>& errors) {
  std::string joined;
  for (const auto& error : errors) {
    joined += (joined.empty() ? "" : "; ") + error;
  }
  return joined;
}

template <typename T>
std::string formatNumber(T value) {
  std::ostringstream stream;
  stream.precision(4);
  stream << value;
  return stream.str();
}

// Median of `values` (reorders them). `values` must not be empty.
double median(std::vector<float>* values) {
  const auto middle = values->begin() + static_cast<std::ptrdiff_t>(values->size() / 2);
  std::nth_element(values->begin(), middle, values->end());
  return *middle;
}

// Value at `fraction` (0..1) of the sorted `values` (reorders them). `values` must not be empty.
double percentile(std::vector<float>* values, double fraction) {
  const auto index = static_cast<std::ptrdiff_t>(
      std::lround(fraction * static_cast<double>(values->size() - 1)));
  const auto nth = values->begin() + index;
  std::nth_element(values->begin(), nth, values->end());
  return *nth;
}

// Thickness of a blob: the diameter of the largest disc inside it, px. A mismatched strip along an
// occlusion edge can have a target's area but not its thickness.
double blobThickness(const cv::Mat& blob_region) {
  cv::Mat padded;  // a zero border, so the blob's edge at the box edge counts as an edge
  cv::copyMakeBorder(blob_region, padded, 1, 1, 1, 1, cv::BORDER_CONSTANT, cv::Scalar(0));
  cv::Mat distance;
  cv::distanceTransform(padded, distance, cv::DIST_L2, cv::DIST_MASK_5);
  double max_distance = 0.0;
  cv::minMaxLoc(distance, nullptr, &max_distance);
  return 2.0 * max_distance;
}

// Disparity of a point `depth_band_m` behind the one at disparity `disparity_px`.
double disparityBehind(const StereoGeometry& geometry, double disparity_px, double depth_band_m) {
  const double focal_baseline = geometry.focal_px * geometry.baseline_m;
  return focal_baseline / (focal_baseline / disparity_px + depth_band_m);
}

}  // namespace

std::vector<std::string> validateParams(const DetectorParams& p) {
  std::vector<std::string> errors;
  auto require = [&errors](bool ok, const std::string& field, const std::string& rule, double got) {
    if (!ok) errors.push_back(field + " " + rule + " (got " + formatNumber(got) + ")");
  };
  require(p.median_kernel_px == 0 || p.median_kernel_px == 1 || p.median_kernel_px == 3 ||
              p.median_kernel_px == 5,
          "median_kernel_px", "must be 0, 1 (off), 3 or 5", p.median_kernel_px);
  require(std::isfinite(p.gaussian_sigma_px) && p.gaussian_sigma_px >= 0.0 &&
              p.gaussian_sigma_px <= 10.0,
          "gaussian_sigma_px", "must be in [0, 10] (0: off)", p.gaussian_sigma_px);
  require(p.closest_min_pixels >= 1, "closest_min_pixels", "must be >= 1", p.closest_min_pixels);
  require(std::isfinite(p.target_depth_m) && p.target_depth_m >= 0.0, "target_depth_m",
          "must be >= 0", p.target_depth_m);
  require(std::isfinite(p.threshold_margin_px) && p.threshold_margin_px >= 0.0,
          "threshold_margin_px", "must be >= 0", p.threshold_margin_px);
  require(std::isfinite(p.face_percentile) && p.face_percentile >= 0.5 && p.face_percentile <= 1.0,
          "face_percentile", "must be in [0.5, 1]", p.face_percentile);
  require(std::isfinite(p.face_depth_band_m) && p.face_depth_band_m >= 0.0, "face_depth_band_m",
          "must be >= 0", p.face_depth_band_m);
  require(std::isfinite(p.face_min_band_px) && p.face_min_band_px >= 0.0, "face_min_band_px",
          "must be >= 0", p.face_min_band_px);
  require(p.min_blob_area_px >= 1, "min_blob_area_px", "must be >= 1", p.min_blob_area_px);
  require(std::isfinite(p.min_blob_thickness_px) && p.min_blob_thickness_px >= 0.0,
          "min_blob_thickness_px", "must be >= 0", p.min_blob_thickness_px);
  require(std::isfinite(p.max_blob_area_fraction) && p.max_blob_area_fraction > 0.0 &&
              p.max_blob_area_fraction <= 1.0,
          "max_blob_area_fraction", "must be in (0, 1]", p.max_blob_area_fraction);
  require(p.border_margin_px >= 0, "border_margin_px", "must be >= 0", p.border_margin_px);
  require(std::isfinite(p.min_disparity_px) && p.min_disparity_px > 0.0, "min_disparity_px",
          "must be > 0", p.min_disparity_px);
  require(std::isfinite(p.max_disparity_px) && p.max_disparity_px > p.min_disparity_px,
          "max_disparity_px", "must be > min_disparity_px", p.max_disparity_px);
  require(std::isfinite(p.roi_top_fraction) && p.roi_top_fraction >= 0.0 && p.roi_top_fraction < 1.0,
          "roi_top_fraction", "must be in [0, 1)", p.roi_top_fraction);
  require(std::isfinite(p.roi_bottom_fraction) && p.roi_bottom_fraction > p.roi_top_fraction &&
              p.roi_bottom_fraction <= 1.0,
          "roi_bottom_fraction", "must be in (roi_top_fraction, 1]", p.roi_bottom_fraction);
  require(std::isfinite(p.floor_cut_y_m) && p.floor_cut_y_m > 0.0, "floor_cut_y_m", "must be > 0",
          p.floor_cut_y_m);
  require(std::isfinite(p.ceiling_cut_y_m) && p.ceiling_cut_y_m >= 0.0, "ceiling_cut_y_m",
          "must be >= 0 (0: off)", p.ceiling_cut_y_m);
  require(std::isfinite(p.disparity_sigma_px) && p.disparity_sigma_px > 0.0, "disparity_sigma_px",
          "must be > 0", p.disparity_sigma_px);
  require(std::isfinite(p.centre_sigma_px) && p.centre_sigma_px > 0.0, "centre_sigma_px",
          "must be > 0", p.centre_sigma_px);
  return errors;
}

std::vector<std::string> validateGeometry(const StereoGeometry& g) {
  std::vector<std::string> errors;
  if (!(std::isfinite(g.focal_px) && g.focal_px > 0.0)) {
    errors.push_back("focal length f must be > 0 (got " + formatNumber(g.focal_px) + ")");
  }
  if (!(std::isfinite(g.baseline_m) && g.baseline_m > 0.0)) {
    errors.push_back("baseline T must be > 0 (got " + formatNumber(g.baseline_m) + ")");
  }
  if (!std::isfinite(g.cx_px) || !std::isfinite(g.cy_px)) {
    errors.push_back("principal point must be finite");
  }
  return errors;
}

const char* outcomeName(Outcome outcome) {
  switch (outcome) {
    case Outcome::kFound: return "found";
    case Outcome::kBadInput: return "bad_input";
    case Outcome::kNoValidDisparity: return "no_valid_disparity";
    case Outcome::kNoBlob: return "no_blob";
    case Outcome::kBlobTooSmall: return "blob_too_small";
    case Outcome::kBlobTooLarge: return "blob_too_large";
    case Outcome::kBlobTouchesBorder: return "blob_touches_border";
    case Outcome::kDisparityOutOfRange: return "disparity_out_of_range";
  }
  return "unknown";
}

DisparityDetector::DisparityDetector(const DetectorParams& params) { setParams(params); }

void DisparityDetector::setParams(const DetectorParams& params) {
  const auto errors = validateParams(params);
  if (!errors.empty()) throw std::invalid_argument(joinErrors(errors));
  params_ = params;
}

void reproject(const StereoGeometry& g, const cv::Point2d& centre_px, double disparity_px,
               double centre_sigma_px, double disparity_sigma_px, Eigen::Vector3d* position_m,
               Eigen::Matrix3d* covariance_m2) {
  const double z = g.focal_px * g.baseline_m / disparity_px;
  const double x = (centre_px.x - g.cx_px) * z / g.focal_px;
  const double y = (centre_px.y - g.cy_px) * z / g.focal_px;
  *position_m << x, y, z;

  // Jacobian of (X, Y, Z) with respect to (u, v, d). The d column is -(X, Y, Z)/d: disparity noise
  // moves the point along its line of sight, which is what rotates the depth error off-axis.
  Eigen::Matrix3d jacobian;
  jacobian << z / g.focal_px, 0.0, -x / disparity_px,
              0.0, z / g.focal_px, -y / disparity_px,
              0.0, 0.0, -z / disparity_px;
  const Eigen::Vector3d input_variance(centre_sigma_px * centre_sigma_px,
                                       centre_sigma_px * centre_sigma_px,
                                       disparity_sigma_px * disparity_sigma_px);
  *covariance_m2 = jacobian * input_variance.asDiagonal() * jacobian.transpose();
}

Detection DisparityDetector::detect(const cv::Mat& disparity, const StereoGeometry& geometry,
                                    double search_min_px, double search_max_px,
                                    cv::Rect valid_region) const {
  Detection result;
  const DetectorParams& p = params_;

  // --- Input checks: every failure is a reason, never an exception.
  if (disparity.empty()) {
    result.reason = "empty disparity image";
    return result;
  }
  if (disparity.type() != CV_32FC1) {
    result.reason = "disparity image must be 32-bit float with one channel (OpenCV type " +
                    std::to_string(CV_32FC1) + "), got type " + std::to_string(disparity.type());
    return result;
  }
  const auto geometry_errors = validateGeometry(geometry);
  if (!geometry_errors.empty()) {
    result.reason = "invalid stereo geometry: " + joinErrors(geometry_errors);
    return result;
  }

  // --- Region of interest: the matcher's valid window, cut to the configured rows.
  const cv::Rect image_rect(0, 0, disparity.cols, disparity.rows);
  cv::Rect region = valid_region.area() > 0 ? (valid_region & image_rect) : image_rect;
  const int roi_top = static_cast<int>(std::lround(p.roi_top_fraction * disparity.rows));
  const int roi_bottom = static_cast<int>(std::lround(p.roi_bottom_fraction * disparity.rows));
  region &= cv::Rect(0, roi_top, disparity.cols, std::max(0, roi_bottom - roi_top));
  if (region.area() <= 0) {
    result.reason = "empty region of interest (valid window and roi_top/bottom_fraction do not overlap)";
    return result;
  }

  // --- Valid disparities of the region; everything else 0. Floor cut: a point is lower than
  // floor_cut_y_m below the axis when (v - cy) B / d > floor_cut_y_m, i.e. d < (v - cy) B / cut;
  // the ceiling cut is the same above the axis.
  const float search_min = static_cast<float>(std::max(search_min_px, 0.0));
  const float search_max = static_cast<float>(search_max_px);
  cv::Mat clean(disparity.size(), CV_32FC1, cv::Scalar(0.0f));
  int valid_count = 0;
  for (int v = region.y; v < region.y + region.height; ++v) {
    float floor_min_disparity = 0.0f;  // disparities below this are floor (ceiling) points here
    if (p.floor_cut_enabled && v > geometry.cy_px) {
      floor_min_disparity =
          static_cast<float>((v - geometry.cy_px) * geometry.baseline_m / p.floor_cut_y_m);
    } else if (p.floor_cut_enabled && p.ceiling_cut_y_m > 0.0 && v < geometry.cy_px) {
      floor_min_disparity =
          static_cast<float>((geometry.cy_px - v) * geometry.baseline_m / p.ceiling_cut_y_m);
    }
    const float* in = disparity.ptr<float>(v);
    float* out = clean.ptr<float>(v);
    for (int u = region.x; u < region.x + region.width; ++u) {
      const float d = in[u];
      // NaN fails every comparison, so it is dropped here too.
      if (d > 0.0f && d >= search_min && d <= search_max && d >= floor_min_disparity) {
        out[u] = d;
        ++valid_count;
      }
    }
  }
  result.valid_pixels = valid_count;
  const int needed = p.closest_min_pixels;
  if (valid_count < needed) {
    result.outcome = Outcome::kNoValidDisparity;
    result.reason = "only " + std::to_string(valid_count) +
                    " valid disparity pixels in the region of interest (need " +
                    std::to_string(needed) + ")";
    return result;
  }

  // --- Filter (the paper's step 2). Invalid pixels are 0, so the median also removes isolated
  // speckles and trims the edge "fattening" of block matching.
  cv::Mat filtered = clean;
  if (p.median_kernel_px >= 3) {
    cv::medianBlur(clean, filtered, p.median_kernel_px);
  }
  if (p.gaussian_sigma_px > 0.0) {
    cv::GaussianBlur(filtered, filtered, cv::Size(0, 0), p.gaussian_sigma_px);
  }

  // --- Closest object: walk a 1/16 px histogram down from the largest disparity until
  // closest_min_pixels pixels are collected. This is a percentile defined by a pixel count, so it
  // does not depend on how much of the scene happens to be valid.
  cv::Mat filtered_region = filtered(region);
  double max_value = 0.0;
  cv::minMaxLoc(filtered_region, nullptr, &max_value);
  if (!(max_value > 0.0)) {
    result.outcome = Outcome::kNoValidDisparity;
    result.reason = "no valid disparity left after filtering";
    return result;
  }
  const int bins = static_cast<int>(std::ceil(max_value * kHistogramBinsPerPx)) + 1;
  std::vector<int> histogram(static_cast<std::size_t>(bins), 0);
  int filtered_count = 0;
  for (int v = 0; v < filtered_region.rows; ++v) {
    const float* row = filtered_region.ptr<float>(v);
    for (int u = 0; u < filtered_region.cols; ++u) {
      if (row[u] > 0.0f) {
        ++histogram[static_cast<std::size_t>(row[u] * kHistogramBinsPerPx)];
        ++filtered_count;
      }
    }
  }
  if (filtered_count < needed) {
    result.outcome = Outcome::kNoValidDisparity;
    result.reason = "only " + std::to_string(filtered_count) +
                    " valid disparity pixels after filtering (need " + std::to_string(needed) + ")";
    return result;
  }
  cv::Mat mask(disparity.size(), CV_8UC1);
  int blob_area = 0;
  int largest_skipped_area = 0;
  for (;;) {
    int collected = 0;
    int closest_bin = bins - 1;
    for (; closest_bin > 0; --closest_bin) {
      collected += histogram[static_cast<std::size_t>(closest_bin)];
      if (collected >= p.closest_min_pixels) break;
    }
    if (collected < p.closest_min_pixels) {
      // Only reachable after skipping: every object in view was too small (its contour and mask are
      // still in `result` for the debug image).
      result.outcome = Outcome::kBlobTooSmall;
      result.reason = "blob too small: every object in view is smaller than min_blob_area_px " +
                      std::to_string(p.min_blob_area_px) + " or thinner than min_blob_thickness_px " +
                      formatNumber(p.min_blob_thickness_px) + " (largest " +
                      std::to_string(largest_skipped_area) + " px)";
      return result;
    }
    const double closest = closest_bin / kHistogramBinsPerPx;
    result.closest_disparity_px = closest;

    // --- Threshold just below it: keep the target's own depth (target_depth_m behind the nearest
    // point), but never closer than threshold_margin_px to the closest disparity.
    const double threshold =
        std::max(std::min(closest - p.threshold_margin_px,
                          disparityBehind(geometry, closest, p.target_depth_m)),
                 1.0 / kHistogramBinsPerPx);
    result.threshold_disparity_px = threshold;
    mask.setTo(cv::Scalar(0));
    cv::Mat mask_region = mask(region);
    cv::compare(filtered_region, threshold, mask_region, cv::CMP_GE);  // writes into `mask`

    // --- Largest blob: the outer contour of the biggest area (the paper's "biggest contour").
    // findContours on the sparse mask costs a tenth of a connected-component labelling.
    std::vector<std::vector<cv::Point>> contours;
    cv::findContours(mask, contours, cv::RETR_EXTERNAL, cv::CHAIN_APPROX_SIMPLE);
    const auto largest = std::max_element(
        contours.begin(), contours.end(), [](const auto& a, const auto& b) {
          const double area_a = cv::contourArea(a), area_b = cv::contourArea(b);
          return area_a < area_b || (area_a == area_b && a.size() < b.size());
        });
    if (largest == contours.end()) {
      result.outcome = result.near_objects_skipped > 0 ? Outcome::kBlobTooSmall : Outcome::kNoBlob;
      result.reason = result.near_objects_skipped > 0
                          ? "blob too small: every object in view is smaller than min_blob_area_px " +
                                std::to_string(p.min_blob_area_px)
                          : "no blob above the threshold disparity " + formatNumber(threshold) + " px";
      return result;
    }
    result.contour = *largest;
    result.bounding_box = cv::boundingRect(result.contour);
    // The blob: thresholded pixels inside the contour (holes of invalid disparity stay out).
    result.mask = cv::Mat(disparity.size(), CV_8UC1, cv::Scalar(0));
    cv::drawContours(result.mask, std::vector<std::vector<cv::Point>>{result.contour}, 0,
                     cv::Scalar(255), cv::FILLED);
    cv::Mat blob_region = result.mask(result.bounding_box);
    cv::bitwise_and(blob_region, mask(result.bounding_box), blob_region);
    blob_area = cv::countNonZero(blob_region);
    result.blob_thickness_px = blobThickness(blob_region);
    const bool plausible_size = blob_area >= p.min_blob_area_px &&
                                result.blob_thickness_px >= p.min_blob_thickness_px;
    if (plausible_size || result.near_objects_skipped >= kMaxNearObjectsSkipped) {
      break;
    }

    // --- Everything at this depth is smaller than a target can be: mismatches at occlusion edges,
    // speckles, dust. Remove it and look behind it, so it cannot hide the target.
    if (filtered.data == clean.data) {  // no filter ran: keep the raw values for the depth
      filtered = clean.clone();
      filtered_region = filtered(region);
    }
    for (int v = 0; v < filtered_region.rows; ++v) {
      float* row = filtered.ptr<float>(region.y + v) + region.x;
      const std::uint8_t* mask_row = mask_region.ptr<std::uint8_t>(v);
      for (int u = 0; u < filtered_region.cols; ++u) {
        if (mask_row[u] != 0) {
          --histogram[static_cast<std::size_t>(row[u] * kHistogramBinsPerPx)];
          row[u] = 0.0f;
        }
      }
    }
    ++result.near_objects_skipped;
    largest_skipped_area = std::max(largest_skipped_area, blob_area);
  }

  // --- The blob's measured (unfiltered) disparities: the median filter chose the pixels, the raw
  // values give the depth, so the filter cannot bias it.
  std::vector<float> blob_disparities;
  std::vector<cv::Point> blob_points;
  blob_disparities.reserve(static_cast<std::size_t>(blob_area));
  blob_points.reserve(static_cast<std::size_t>(blob_area));
  const cv::Rect& box = result.bounding_box;
  for (int v = box.y; v < box.y + box.height; ++v) {
    const std::uint8_t* blob_row = result.mask.ptr<std::uint8_t>(v);
    const float* clean_row = clean.ptr<float>(v);
    for (int u = box.x; u < box.x + box.width; ++u) {
      if (blob_row[u] != 0 && clean_row[u] > 0.0f) {
        blob_disparities.push_back(clean_row[u]);
        blob_points.emplace_back(u, v);
      }
    }
  }
  result.blob_pixels = static_cast<int>(blob_disparities.size());

  // --- The visible face: the blob's nearest depth layer (the panels and body sides lie behind it).
  if (!blob_disparities.empty()) {
    std::vector<float> sorted = blob_disparities;
    const double reference = percentile(&sorted, p.face_percentile);
    const double band = std::max(p.face_min_band_px,
                                 reference - disparityBehind(geometry, reference, p.face_depth_band_m));
    const float face_min = static_cast<float>(reference - band);
    std::vector<float> face_disparities;
    double sum_u = 0.0, sum_v = 0.0;
    for (std::size_t i = 0; i < blob_disparities.size(); ++i) {
      if (blob_disparities[i] >= face_min) {
        face_disparities.push_back(blob_disparities[i]);
        sum_u += blob_points[i].x;
        sum_v += blob_points[i].y;
      }
    }
    result.face_pixels = static_cast<int>(face_disparities.size());
    const double face_count = static_cast<double>(face_disparities.size());
    result.centre_px = cv::Point2d(sum_u / face_count, sum_v / face_count);
    result.disparity_px = median(&face_disparities);
    reproject(geometry, result.centre_px, result.disparity_px, p.centre_sigma_px,
              p.disparity_sigma_px, &result.position_m, &result.covariance_m2);
    result.range_m = result.position_m.norm();
  }

  // --- Plausibility, with the numbers in the reason so a user can tune live.
  const int margin = p.border_margin_px;
  const bool touches_left = box.x <= region.x + margin;
  const bool touches_right = box.x + box.width >= region.x + region.width - margin;
  const bool touches_top = box.y <= region.y + margin;
  const bool touches_bottom = box.y + box.height >= region.y + region.height - margin;
  if (result.blob_pixels < p.min_blob_area_px) {
    result.outcome = Outcome::kBlobTooSmall;
    result.reason = "blob too small: " + std::to_string(result.blob_pixels) + " px < min_blob_area_px " +
                    std::to_string(p.min_blob_area_px);
  } else if (result.blob_thickness_px < p.min_blob_thickness_px) {
    result.outcome = Outcome::kBlobTooSmall;
    result.reason = "blob too thin: " + formatNumber(result.blob_thickness_px) +
                    " px < min_blob_thickness_px " + formatNumber(p.min_blob_thickness_px);
  } else if (touches_left || touches_right || touches_top || touches_bottom) {
    result.outcome = Outcome::kBlobTouchesBorder;
    std::string sides;
    if (touches_left) sides += " left";
    if (touches_right) sides += " right";
    if (touches_top) sides += " top";
    if (touches_bottom) sides += " bottom";
    result.reason = "blob touches the border of the valid region:" + sides;
  } else if (blob_area > p.max_blob_area_fraction * region.area()) {
    result.outcome = Outcome::kBlobTooLarge;
    result.reason = "blob too large: " + std::to_string(blob_area) + " px > max_blob_area_fraction " +
                    formatNumber(p.max_blob_area_fraction) + " of " + std::to_string(region.area()) +
                    " px";
  } else if (result.disparity_px < p.min_disparity_px || result.disparity_px > p.max_disparity_px) {
    result.outcome = Outcome::kDisparityOutOfRange;
    result.reason = "blob disparity " + formatNumber(result.disparity_px) + " px outside [" +
                    formatNumber(p.min_disparity_px) + ", " + formatNumber(p.max_disparity_px) + "]";
  } else {
    result.found = true;
    result.outcome = Outcome::kFound;
  }
  return result;
}

cv::Mat renderDebugImage(const cv::Mat& disparity, const Detection& detection,
                         double display_max_disparity_px) {
  if (disparity.empty() || disparity.type() != CV_32FC1) {
    cv::Mat blank(480, 640, CV_8UC3, cv::Scalar(0, 0, 0));
    cv::putText(blank, detection.reason.empty() ? "no disparity image" : detection.reason,
                cv::Point(10, 30), cv::FONT_HERSHEY_SIMPLEX, 0.5, cv::Scalar(0, 0, 255), 1);
    return blank;
  }
  // Near = bright; NaN and negative (invalid) become 0 through the saturating conversion.
  cv::Mat grey;
  const double scale = display_max_disparity_px > 0.0 ? 255.0 / display_max_disparity_px : 1.0;
  cv::Mat finite = disparity.clone();
  cv::patchNaNs(finite, 0.0);
  finite.convertTo(grey, CV_8UC1, scale);
  cv::Mat image;
  cv::cvtColor(grey, image, cv::COLOR_GRAY2BGR);

  const cv::Scalar colour = detection.found ? cv::Scalar(0, 220, 0) : cv::Scalar(0, 0, 255);
  if (!detection.mask.empty() && detection.mask.size() == image.size()) {
    cv::Mat tint(image.size(), CV_8UC3, colour);
    cv::Mat blended;
    cv::addWeighted(image, 0.5, tint, 0.5, 0.0, blended);
    blended.copyTo(image, detection.mask);
  }
  if (!detection.contour.empty()) {
    cv::polylines(image, std::vector<std::vector<cv::Point>>{detection.contour}, true, colour, 2);
  }
  if (detection.blob_pixels > 0) {
    cv::drawMarker(image, cv::Point(static_cast<int>(std::lround(detection.centre_px.x)),
                                    static_cast<int>(std::lround(detection.centre_px.y))),
                   cv::Scalar(255, 255, 0), cv::MARKER_CROSS, 20, 2);
  }
  std::ostringstream text;
  text.precision(3);
  if (detection.found) {
    text << std::fixed << "Z " << detection.position_m.z() << " m  d " << detection.disparity_px
         << " px  " << detection.blob_pixels << " px";
  } else {
    text << detection.reason;
  }
  cv::putText(image, text.str(), cv::Point(10, 25), cv::FONT_HERSHEY_SIMPLEX, 0.55, colour, 2);
  return image;
}

}  // namespace disparity
}  // namespace docking_perception
