#include "docking_perception/disparity/disparity_detector.h"
#include "docking_perception/debug_caption.h"
#include "docking_perception/disparity/footprint_fit.h"
#include "number_text.h"

#include <docking_settings/setting_info.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <sstream>
#include <stdexcept>

#include <climits>
#include <iomanip>
#include <functional>
#include <limits>
#include <utility>

#include <opencv2/imgproc.hpp>
#include <yaml-cpp/yaml.h>

namespace docking_perception {
namespace disparity {
namespace {

// Sub-pixel resolution of the closest-disparity histogram: OpenCV's matchers give 1/16 px.
constexpr double kHistogramBinsPerPx = 16.0;
// How many nearer depth bands (too small, too thin or not target-shaped) the search may look behind
// before it gives up: a lab has walls, furniture and people in front of a target 6 m away.
constexpr int kMaxNearObjectsSkipped = 8;
// Blobs of one band measured, largest first (the rest are crumbs).
constexpr std::size_t kMaxBlobsPerBand = 6;
// Yaw steps of the mockup's outline in shapeBounds (0 to 90 deg; the outline is symmetric).
constexpr int kYawSteps = 90;
// Constants of the method, not tuning:
// the band's threshold stays at least this far below the closest disparity (the matcher's noise on a flat
// face is a fraction of a pixel);
constexpr double kThresholdMarginPx = 1.0;
// a blob this close to the valid region's edge is cut by it (the median filter's reach and a pixel);
constexpr int kBorderMarginPx = 2;
// the blob's nearest (face) layer: within this depth of its reference disparity (the panels and the box's
// sides lie 0.15 m and more behind the face), and never thinner than the matcher's sub-pixel noise.
constexpr double kFaceDepthBandM = 0.10;
constexpr double kFaceMinBandPx = 0.25;
// Threshold levels tried inside a blob larger than the mockup: at least this far apart (2 histogram
// bins), and at most this many (at 2 m the band is 6 px deep: 48 levels cost 50 ms a frame).
constexpr double kSplitLevelStepPx = 2.0 / kHistogramBinsPerPx;
constexpr int kMaxSplitLevels = 16;
// The blob's nearest (face) layer is referred to this percentile of its disparities (0.7-0.98 swept on
// far_approach.bag, docs/TUNING.md).
constexpr double kFacePercentile = 0.9;
// A profile point this near the fitted footprint (plus the depth noise at its range) is on it: the face's and
// panels' thickness and a column median's noise.
constexpr double kFootprintInlierDistanceM = 0.05;

std::string joinErrors(const std::vector<std::string>& errors) {
  std::string joined;
  for (const auto& error : errors) {
    joined += (joined.empty() ? "" : "; ") + error;
  }
  return joined;
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


// One blob of a depth band: its outer contour, bounding box and the band's pixels inside the contour.
struct BlobCandidate {
  bool valid = false;
  std::vector<cv::Point> contour;
  cv::Rect box;
  cv::Mat local_mask;  // CV_8U, box-sized: 255 on the blob's pixels
  int area = 0;
  double thickness_px = 0.0;
  BlobShape shape;
  std::string misfit;  // why it is not the target (shape check), empty when it may be
};

BlobCandidate makeCandidate(const std::vector<cv::Point>& contour, const cv::Mat& band_mask) {
  BlobCandidate candidate;
  candidate.valid = true;
  candidate.contour = contour;
  candidate.box = cv::boundingRect(contour);
  // The blob: thresholded pixels inside the contour (holes of invalid disparity stay out).
  candidate.local_mask = cv::Mat(candidate.box.size(), CV_8UC1, cv::Scalar(0));
  cv::drawContours(candidate.local_mask, std::vector<std::vector<cv::Point>>{contour}, 0,
                   cv::Scalar(255), cv::FILLED, cv::LINE_8, cv::noArray(), INT_MAX,
                   -candidate.box.tl());
  cv::bitwise_and(candidate.local_mask, band_mask(candidate.box), candidate.local_mask);
  candidate.area = cv::countNonZero(candidate.local_mask);
  candidate.thickness_px = blobThickness(candidate.local_mask);
  return candidate;
}

// Metric size of a blob at its median raw disparity (the filter chose the pixels).
BlobShape measureBlobShape(const BlobCandidate& blob, const cv::Mat& clean,
                           const StereoGeometry& geometry) {
  std::vector<float> values;
  values.reserve(static_cast<std::size_t>(blob.area));
  for (int v = 0; v < blob.box.height; ++v) {
    const std::uint8_t* mask_row = blob.local_mask.ptr<std::uint8_t>(v);
    const float* row = clean.ptr<float>(blob.box.y + v) + blob.box.x;
    for (int u = 0; u < blob.box.width; ++u) {
      if (mask_row[u] != 0 && row[u] > 0.0f) values.push_back(row[u]);
    }
  }
  BlobShape shape;
  shape.fill = static_cast<double>(blob.area) / std::max(1, blob.box.area());
  if (values.empty()) return shape;
  const double focal_baseline = geometry.focal_px * geometry.baseline_m;
  const double near_d = percentile(&values, 0.9), far_d = percentile(&values, 0.1);
  shape.range_z_m = focal_baseline / median(&values);
  shape.width_m = blob.box.width * shape.range_z_m / geometry.focal_px;
  shape.height_m = blob.box.height * shape.range_z_m / geometry.focal_px;
  shape.depth_extent_m = focal_baseline / far_d - focal_baseline / near_d;
  return shape;
}

// Whether `box` reaches within `margin` of the edge of `region` (the blob is cut there).
bool touchesBorder(const cv::Rect& box, const cv::Rect& region, int margin) {
  return box.x <= region.x + margin || box.x + box.width >= region.x + region.width - margin ||
         box.y <= region.y + margin || box.y + box.height >= region.y + region.height - margin;
}

// Whether `box` reaches an edge of `region` that is an edge of the tracking window, not of the full image
// (`image_size`: the disparity image's size; the region's left edge is the matcher's blind band, a window
// edge only when the window does not start at the image's left edge).
bool crossesWindowEdge(const cv::Rect& box, const cv::Rect& region, int margin, const ImageWindow& window,
                       cv::Size image_size) {
  if (!window.isWindow()) return false;
  const bool left_is_window = window.offset.x > 0;
  const bool right_is_window = window.offset.x + image_size.width < window.full_size.width;
  const bool top_is_window = window.offset.y > 0;
  const bool bottom_is_window = window.offset.y + image_size.height < window.full_size.height;
  return (left_is_window && box.x <= region.x + margin) ||
         (right_is_window && box.x + box.width >= region.x + region.width - margin) ||
         (top_is_window && box.y <= region.y + margin) ||
         (bottom_is_window && box.y + box.height >= region.y + region.height - margin);
}

// Empty when the blob can be the mockup; otherwise what does not fit, with the numbers. A blob cut by
// the border (`cut`) is only held to the upper bounds: the target partly out of view must stop the
// search (and be reported as touching the border), not be looked behind.
std::string shapeMismatch(const BlobShape& shape, const ShapeBounds& bounds,
                          const RigLimits& limits, double focal_px, bool cut) {
  if (!(shape.range_z_m > 0.0)) return "no valid disparity inside the blob";
  const double pixel_m = limits.shape_margin_px * shape.range_z_m / focal_px;
  const double k = kShapeToleranceFraction;
  auto check = [&](const char* what, double value, double low, double high) -> std::string {
    low = cut ? 0.0 : std::max(0.0, low * (1.0 - k) - pixel_m);
    high = high * (1.0 + k) + pixel_m;
    if (value >= low && value <= high) return "";
    return std::string(what) + " " + formatNumber(value) + " m outside [" + formatNumber(low) + ", " +
           formatNumber(high) + "] m of the mockup";
  };
  std::string misfit = check("width", shape.width_m, bounds.min_width_m, bounds.max_width_m);
  if (misfit.empty()) misfit = check("height", shape.height_m, bounds.min_height_m, bounds.max_height_m);
  if (misfit.empty()) return "";
  return misfit + " (blob at " + formatNumber(shape.range_z_m) + " m, " +
         formatNumber(shape.width_m) + " x " + formatNumber(shape.height_m) + " m, fill " +
         formatNumber(shape.fill) + ")";
}

// Rough position of a blob (its pixel centroid at its median depth), for the hint's gate.
Eigen::Vector3d candidatePosition(const BlobCandidate& blob, const StereoGeometry& geometry) {
  const cv::Moments moments = cv::moments(blob.local_mask, true);
  if (!(moments.m00 > 0.0) || !(blob.shape.range_z_m > 0.0)) {
    return Eigen::Vector3d::Constant(std::numeric_limits<double>::infinity());
  }
  const double u = blob.box.x + moments.m10 / moments.m00;
  const double v = blob.box.y + moments.m01 / moments.m00;
  const double z = blob.shape.range_z_m;
  return {(u - geometry.cx_px) * z / geometry.focal_px, (v - geometry.cy_px) * z / geometry.focal_px, z};
}

// Empty when the blob's centre (`position`, optical frame: y down) is within kMaxCentreOffsetM of the port's
// height (level_floor: where the port of a target on the same floor is); otherwise why not.
std::string heightMismatch(const Eigen::Vector3d& position, const DetectorParams& p, const RigLimits& limits) {
  const double offset = position.y() - limits.port_y_m;
  if (!p.level_floor || std::abs(offset) <= kMaxCentreOffsetM) return "";
  return "centre " + formatNumber(std::abs(offset)) + " m " + (offset < 0.0 ? "above" : "below") +
         " the port's height > " + formatNumber(kMaxCentreOffsetM) + " m (blob at " + formatNumber(position.z()) +
         " m; level_floor: the port at its mount's height)";
}

// Copies the blob into the detection (contour, box, full-size mask, size figures).
void adoptBlob(const BlobCandidate& blob, cv::Size image_size, Detection* result) {
  result->contour = blob.contour;
  result->bounding_box = blob.box;
  result->mask = cv::Mat(image_size, CV_8UC1, cv::Scalar(0));
  blob.local_mask.copyTo(result->mask(blob.box));
  result->blob_thickness_px = blob.thickness_px;
  result->shape = blob.shape;
}

// The component of the pixels of `blob` at or above `level_px` that contains `inside` (a pixel of
// `blob`), within blob.box: its bounding box, empty when `inside` is below the level.
cv::Rect componentAround(const BlobCandidate& blob, const cv::Mat& filtered, double level_px,
                         cv::Point inside) {
  cv::Mat level_mask;
  cv::compare(filtered(blob.box), level_px, level_mask, cv::CMP_GE);
  cv::bitwise_and(level_mask, blob.local_mask, level_mask);
  const cv::Point seed = inside - blob.box.tl();
  if (level_mask.at<std::uint8_t>(seed) == 0) return cv::Rect();
  cv::Rect component;
  cv::floodFill(level_mask, seed, cv::Scalar(128), &component, cv::Scalar(0), cv::Scalar(0), 8);
  return component + blob.box.tl();
}

// Inside a blob larger than the mockup (the target merged with a box beside or behind it through
// block matching's smeared depth edges), the nearer parts at each threshold level above the band's:
// the largest over all levels that has the mockup's shape, at its height, and is isolated - the
// component holding it split_depth_step_m deeper is still within the mockup's upper bounds, so a bump
// of a box's surface (which grows into the whole box) is not taken. Largest, not first: a mismatched
// sliver at an occlusion edge can pass at a deep level where the face has not separated yet.
// Invalid candidate when there is none.
BlobCandidate splitMergedBlob(const BlobCandidate& merged, const cv::Mat& filtered,
                              const cv::Mat& clean, const StereoGeometry& geometry,
                              const ShapeBounds& bounds, const DetectorParams& p, const RigLimits& limits,
                              const cv::Rect& region, double band_threshold_px) {
  double top_px = 0.0;
  cv::minMaxLoc(filtered(merged.box), nullptr, &top_px, nullptr, nullptr, merged.local_mask);
  cv::Mat level_mask(filtered.size(), CV_8UC1, cv::Scalar(0));
  const double focal_baseline = geometry.focal_px * geometry.baseline_m;
  BlobCandidate best;
  const double step_px =
      std::max(kSplitLevelStepPx, (top_px - band_threshold_px) / (kMaxSplitLevels + 1));
  for (double level = band_threshold_px + step_px; level < top_px; level += step_px) {
    cv::Mat level_box = level_mask(merged.box);
    cv::compare(filtered(merged.box), level, level_box, cv::CMP_GE);
    cv::bitwise_and(level_box, merged.local_mask, level_box);
    std::vector<std::vector<cv::Point>> contours;
    cv::findContours(level_box.clone(), contours, cv::RETR_EXTERNAL, cv::CHAIN_APPROX_SIMPLE,
                     merged.box.tl());
    for (const auto& contour : contours) {
      const double contour_area = cv::contourArea(contour);
      if (contour_area < p.min_blob_area_px / 2.0 || (best.valid && contour_area < best.area / 2.0)) {
        continue;  // crumbs, or too small to beat the best, cheaply
      }
      BlobShape outline;  // the part's bounding box at the level's depth: most parts are too large
      outline.range_z_m = focal_baseline / level;
      const cv::Rect outline_box = cv::boundingRect(contour);
      outline.width_m = outline_box.width * outline.range_z_m / geometry.focal_px;
      outline.height_m = outline_box.height * outline.range_z_m / geometry.focal_px;
      if (!shapeMismatch(outline, bounds, limits, geometry.focal_px, /*cut=*/true).empty()) continue;
      BlobCandidate part = makeCandidate(contour, level_mask);
      if (part.area < p.min_blob_area_px || part.thickness_px < p.min_blob_thickness_px ||
          touchesBorder(part.box, region, kBorderMarginPx)) {
        continue;
      }
      part.shape = measureBlobShape(part, clean, geometry);
      if (!shapeMismatch(part.shape, bounds, limits, geometry.focal_px, /*cut=*/false).empty() ||
          !heightMismatch(candidatePosition(part, geometry), p, limits).empty()) {
        continue;
      }
      const double part_disparity = focal_baseline / part.shape.range_z_m;
      const double parent_level = std::max(
          band_threshold_px, disparityBehind(geometry, part_disparity, p.split_depth_step_m));
      BlobShape parent = part.shape;
      const cv::Rect parent_box = componentAround(merged, filtered, parent_level, contour.front());
      parent.width_m = parent_box.width * parent.range_z_m / geometry.focal_px;
      parent.height_m = parent_box.height * parent.range_z_m / geometry.focal_px;
      if (shapeMismatch(parent, bounds, limits, geometry.focal_px, /*cut=*/true).empty() &&
          (!best.valid || part.area > best.area)) {
        best = std::move(part);
      }
    }
  }
  return best;
}

// The port from the mockup's footprint fitted to the blob's column profile (footprint_fit.h): sets the
// detection's centre (the port's image point; its row the blob's median row, the mockup being as high
// above the port as below) and disparity, so that reproject() gives the port and its covariance.
// Not passed: `reason` says why no footprint could be fitted.
StageOutcome portFromFootprint(const std::vector<cv::Point>& points, const std::vector<float>& disparities,
                               const StereoGeometry& geometry, const TargetShape& shape, Detection* result,
                               std::string* reason) {
  std::vector<int> columns, rows;
  columns.reserve(points.size());
  rows.reserve(points.size());
  for (const cv::Point& point : points) {
    columns.push_back(point.x);
    rows.push_back(point.y);
  }
  FootprintFitParams fit_params;
  fit_params.inlier_distance_m = kFootprintInlierDistanceM;
  const FootprintFit fit = fitFootprint(columnProfile(columns, disparities, geometry), shape, geometry, fit_params);
  if (!fit.valid) {
    *reason = "footprint fit: only " + std::to_string(fit.profile_points) + " image columns with depth (need " +
              std::to_string(kMinProfilePoints) + ")";
    return PortOutcome::kTooFewColumns;
  }
  result->footprint_yaw_rad = fit.yaw_rad;
  result->footprint_inlier_fraction = fit.inlier_fraction;
  auto middle = rows.begin() + static_cast<std::ptrdiff_t>(rows.size() / 2);
  std::nth_element(rows.begin(), middle, rows.end());
  const double z = fit.port_xz.y();
  result->centre_px = cv::Point2d(geometry.cx_px + geometry.focal_px * fit.port_xz.x() / z, *middle);
  result->disparity_px = geometry.focal_px * geometry.baseline_m / z;
  result->footprint_fitted = true;
  return PortOutcome::kPassed;
}

// Extent of the mockup's outline across the line of sight at `yaw` (0: face-on): the box's columns at
// full height, the panels' at theirs.
double outlineWidthAtYaw(const TargetShape& t, double yaw) {
  const double c = std::cos(yaw), s = std::sin(yaw);
  // Projection of a point (x forward out of the face, y to the side) on the image's horizontal.
  auto across = [&](double x, double y) { return y * c + x * s; };
  const double half_w = t.face_width_m / 2.0;
  const double box_a = std::min({across(0, -half_w), across(-t.body_depth_m, -half_w)});
  const double box_b = std::max({across(0, half_w), across(-t.body_depth_m, half_w)});
  const double mid_x = -t.body_depth_m / 2.0;  // panels at mid depth
  const double left_a = std::min(across(mid_x, -half_w - t.panel_span_m), across(mid_x, -half_w));
  const double left_b = std::max(across(mid_x, -half_w - t.panel_span_m), across(mid_x, -half_w));
  const double right_a = std::min(across(mid_x, half_w), across(mid_x, half_w + t.panel_span_m));
  const double right_b = std::max(across(mid_x, half_w), across(mid_x, half_w + t.panel_span_m));
  return std::max({box_b, left_b, right_b}) - std::min({box_a, left_a, right_a});
}

}  // namespace

ShapeBounds shapeBounds(const TargetShape& shape) {
  ShapeBounds bounds;
  bounds.min_width_m = std::numeric_limits<double>::infinity();
  for (int step = 0; step <= kYawSteps; ++step) {
    const double width = outlineWidthAtYaw(shape, 0.5 * M_PI * step / kYawSteps);
    bounds.min_width_m = std::min(bounds.min_width_m, width);
    bounds.max_width_m = std::max(bounds.max_width_m, width);
  }
  // The box is as tall as the face and shows its full height from any yaw.
  bounds.min_height_m = shape.face_height_m;
  bounds.max_height_m = std::max(shape.face_height_m, shape.panel_height_m);
  return bounds;
}

namespace {

YAML::Node loadYamlFile(const std::string& path, const char* what) {
  try {
    return YAML::LoadFile(path);
  } catch (const std::exception& error) {
    throw std::runtime_error(std::string("cannot read ") + what + " " + path + ": " + error.what());
  }
}

// The number at `node` (field `field` of file `path`), finite and >= 0; throws std::runtime_error naming both.
double nonNegativeNumber(const YAML::Node& node, const std::string& path, const std::string& field) {
  if (!node || !node.IsScalar()) throw std::runtime_error(path + ": missing field '" + field + "'");
  double value = 0.0;
  try {
    value = node.as<double>();
  } catch (const std::exception&) {
    throw std::runtime_error(path + ": field '" + field + "' is not a number");
  }
  if (!(std::isfinite(value) && value >= 0.0)) {
    throw std::runtime_error(path + ": field '" + field + "' must be >= 0");
  }
  return value;
}

// The height (z, the third of xyz_m) of a mount: robot.yaml's cameras and target.yaml's port.
double mountHeight(const YAML::Node& mount, const std::string& path, const std::string& field) {
  const YAML::Node xyz = mount["xyz_m"];
  if (!xyz || !xyz.IsSequence() || xyz.size() != 3) {
    throw std::runtime_error(path + ": field '" + field + ".xyz_m' must be a list of 3 numbers");
  }
  return nonNegativeNumber(xyz[2], path, field + ".xyz_m[2]");
}

}  // namespace

RigGeometry loadRigGeometry(const std::string& robot_yaml_path, const std::string& target_yaml_path,
                            int matcher_window_px) {
  RigGeometry rig;
  const YAML::Node robot = loadYamlFile(robot_yaml_path, "robot description");
  rig.camera_height_m = mountHeight(robot["chaser"]["cameras"]["stereo_left"], robot_yaml_path,
                                    "chaser.cameras.stereo_left");
  const YAML::Node target = loadYamlFile(target_yaml_path, "target model");
  rig.port_height_m = mountHeight(target["target"]["mount"], target_yaml_path, "target.mount");
  rig.matcher_window_px = matcher_window_px;
  return rig;
}

TargetShape loadTargetShape(const std::string& path) {
  const YAML::Node root = loadYamlFile(path, "target model");
  auto number = [&](const YAML::Node& node, const std::string& field) { return nonNegativeNumber(node, path, field); };
  const YAML::Node target = root["target"];
  TargetShape shape;
  shape.face_width_m = number(target["face"]["width_m"], "target.face.width_m");
  shape.face_height_m = number(target["face"]["height_m"], "target.face.height_m");
  shape.body_depth_m = number(target["body"]["depth_m"], "target.body.depth_m");
  shape.panel_span_m = 0.0;
  shape.panel_height_m = 0.0;
  if (target["solar_panels"]) {
    shape.panel_span_m = number(target["solar_panels"]["span_m"], "target.solar_panels.span_m");
    shape.panel_height_m = number(target["solar_panels"]["height_m"], "target.solar_panels.height_m");
    // offset_x_m is the panels' x in frame `target` (<= 0: behind the face); absent: mid-depth.
    const YAML::Node offset = target["solar_panels"]["offset_x_m"];
    shape.panel_offset_behind_face_m = 0.5 * shape.body_depth_m;
    if (offset) {
      double x = 1.0;
      try {
        x = offset.as<double>();
      } catch (const std::exception&) {
        throw std::runtime_error(path + ": field 'target.solar_panels.offset_x_m' is not a number");
      }
      if (!(std::isfinite(x) && x <= 0.0 && -x <= shape.body_depth_m)) {
        throw std::runtime_error(path + ": field 'target.solar_panels.offset_x_m' must be in [-body.depth_m, 0]");
      }
      shape.panel_offset_behind_face_m = -x;
    }
  }
  if (!(shape.face_width_m > 0.0 && shape.face_height_m > 0.0)) {
    throw std::runtime_error(path + ": target.face width_m and height_m must be > 0");
  }
  return shape;
}

namespace {

// A rule between settings, or a mockup the checks cannot use: the same error as a setting out of range.
void require(bool ok, const char* key, const std::string& rule) {
  if (!ok) throw docking_settings::ConfigError(key, docking_settings::ConfigProblem::kInvalid, rule);
}

}  // namespace

void validate(const DetectorParams& p, const TargetShape& t, const RigGeometry& rig) {
  docking_settings::validateSettings(p);
  require(p.median_kernel_px != 2 && p.median_kernel_px != 4, "median_kernel_px",
          "must be 0, 1 (off), 3 or 5 (got " + std::to_string(p.median_kernel_px) + ")");
  require(p.max_disparity_px > p.min_disparity_px, "max_disparity_px",
          "must be > min_disparity_px (got " + formatNumber(p.max_disparity_px) + ")");
  require(std::isfinite(t.face_width_m) && t.face_width_m > 0.0 && std::isfinite(t.face_height_m) &&
              t.face_height_m > 0.0,
          "target_yaml", "the mockup's face width and height must be > 0");
  require(std::isfinite(t.body_depth_m) && t.body_depth_m >= 0.0 && std::isfinite(t.panel_span_m) &&
              t.panel_span_m >= 0.0 && std::isfinite(t.panel_height_m) && t.panel_height_m >= 0.0,
          "target_yaml", "the mockup's body depth and panel sizes must be >= 0");
  require(std::isfinite(t.panel_offset_behind_face_m) && t.panel_offset_behind_face_m >= 0.0 &&
              t.panel_offset_behind_face_m <= t.body_depth_m,
          "target_yaml", "the mockup's panels must lie within its body depth");
  require(rig.matcher_window_px > 0, "matcher/correlation_window_size",
          "must be > 0 (got " + std::to_string(rig.matcher_window_px) + ")");
  // The floor cut must lie above the floor, or the floor is the closest object.
  const double floor_cut_m = rigLimits(t, rig).floor_cut_m;
  require(!p.level_floor || (std::isfinite(rig.camera_height_m) && std::isfinite(rig.port_height_m) &&
                             floor_cut_m > 0.0 && floor_cut_m < rig.camera_height_m),
          "level_floor",
          "the floor cut " + formatNumber(floor_cut_m) + " m below the optical axis (the face's lower edge plus " +
              formatNumber(kFloorCutMarginM) + " m) must lie between the axis and the floor " +
              formatNumber(rig.camera_height_m) + " m below it (robot.yaml, target.yaml); false without a floor");
}

RigLimits rigLimits(const TargetShape& shape, const RigGeometry& rig) {
  RigLimits limits;
  limits.port_y_m = rig.camera_height_m - rig.port_height_m;
  limits.floor_cut_m = limits.port_y_m + 0.5 * shape.face_height_m + kFloorCutMarginM;
  limits.band_depth_m = shape.body_depth_m + kBandDepthMarginM;
  limits.shape_margin_px = (rig.matcher_window_px + 1) / 2;
  return limits;
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

DisparityDetector::DisparityDetector(const DetectorParams& params, const TargetShape& shape, const RigGeometry& rig) {
  validate(params, shape, rig);
  params_ = params;
  shape_ = shape;
  rig_ = rig;
  limits_ = rigLimits(shape, rig);
}

void DisparityDetector::setParams(const DetectorParams& params) {
  validate(params, shape_, rig_);
  params_ = params;
}

void reproject(const StereoGeometry& g, const cv::Point2d& centre_px, double disparity_px,
               double point_sigma_px, double disparity_noise_px, Eigen::Vector3d* position_m,
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
  const Eigen::Vector3d input_variance(point_sigma_px * point_sigma_px,
                                       point_sigma_px * point_sigma_px,
                                       disparity_noise_px * disparity_noise_px);
  *covariance_m2 = jacobian * input_variance.asDiagonal() * jacobian.transpose();
}

namespace {

// The images the stages share: the valid raw disparities of the searched region (0 elsewhere), the filtered
// ones the search thresholds (the same data when no filter runs), and the filtered values' histogram.
struct SearchImages {
  cv::Rect region;
  cv::Mat clean;
  cv::Mat filtered;
  std::vector<int> histogram;  // 1/16 px bins of the filtered values > 0 in the region
};

// Everything a blob of a band is judged with.
struct BandContext {
  const DetectorParams& p;
  const RigLimits& limits;
  const StereoGeometry& geometry;
  const ShapeBounds& bounds;
  const SearchHint& hint;
  const ImageWindow& window;
  cv::Size image_size;
};

// What the search keeps from band to band: the chosen blob and those that explain a failure.
struct BandSearchState {
  BlobCandidate chosen, fallback, first_misfit, largest_small;
  // A blob of a band failed the shape check only on a lower bound: it may be the target, degraded (glare,
  // blur, merged holes), so nothing behind it is trusted (issue 11: at 2 m under glare a box stack 1.4 m
  // behind the face was taken).
  bool stop_here = false;
  int largest_skipped_area = 0;
};

// Stage 1, input: the image and geometry usable, and the searched region: the matcher's valid window.
StageOutcome selectRegion(const cv::Mat& disparity, const StereoGeometry& geometry, cv::Rect valid_region,
                          cv::Rect* region, std::string* reason) {
  if (disparity.empty()) {
    *reason = "empty disparity image";
    return InputOutcome::kEmptyImage;
  }
  if (disparity.type() != CV_32FC1) {
    *reason = "disparity image must be 32-bit float with one channel (OpenCV type " + std::to_string(CV_32FC1) +
              "), got type " + std::to_string(disparity.type());
    return InputOutcome::kBadEncoding;
  }
  const auto geometry_errors = validateGeometry(geometry);
  if (!geometry_errors.empty()) {
    *reason = "invalid stereo geometry: " + joinErrors(geometry_errors);
    return InputOutcome::kBadGeometry;
  }
  const cv::Rect image_rect(0, 0, disparity.cols, disparity.rows);
  *region = valid_region.area() > 0 ? (valid_region & image_rect) : image_rect;
  if (region->area() <= 0) {
    *reason = "empty region of interest (the matcher's valid window is outside the image)";
    return InputOutcome::kEmptyRegion;
  }
  return InputOutcome::kPassed;
}

// The region's valid disparities (finite, > 0, inside the matcher's search range and, with level_floor, the floor
// cut) in a copy, everything else 0; returns how many. Floor cut: a point is lower than the cut
// (RigLimits::floor_cut_m) below the axis when (v - cy) B / d > cut, i.e. d < (v - cy) B / cut.
int keepValidDisparities(const cv::Mat& disparity, const StereoGeometry& geometry, double search_min_px,
                         double search_max_px, const DetectorParams& p, const RigLimits& limits,
                         SearchImages* images) {
  const cv::Rect& region = images->region;
  const float search_min = static_cast<float>(std::max(search_min_px, 0.0));
  const float search_max = static_cast<float>(search_max_px);
  images->clean = cv::Mat(disparity.size(), CV_32FC1, cv::Scalar(0.0f));
  int valid_count = 0;
  for (int v = region.y; v < region.y + region.height; ++v) {
    float floor_min_disparity = 0.0f;  // disparities below this are floor points here
    if (p.level_floor && v > geometry.cy_px) {
      floor_min_disparity = static_cast<float>((v - geometry.cy_px) * geometry.baseline_m / limits.floor_cut_m);
    }
    const float* in = disparity.ptr<float>(v);
    float* out = images->clean.ptr<float>(v);
    for (int u = region.x; u < region.x + region.width; ++u) {
      const float d = in[u];
      // NaN fails every comparison, so it is dropped here too.
      if (d > 0.0f && d >= search_min && d <= search_max && d >= floor_min_disparity) {
        out[u] = d;
        ++valid_count;
      }
    }
  }
  return valid_count;
}

// The filter (the paper's step 2) and the histogram of what it leaves; returns how many filtered pixels are
// valid (-1: none). Invalid pixels are 0, so the median also removes isolated speckles and trims the edge
// "fattening" of block matching.
int filterAndCount(const DetectorParams& p, SearchImages* images) {
  images->filtered = images->clean;
  if (p.median_kernel_px >= 3) cv::medianBlur(images->clean, images->filtered, p.median_kernel_px);
  const cv::Mat filtered_region = images->filtered(images->region);
  double max_value = 0.0;
  cv::minMaxLoc(filtered_region, nullptr, &max_value);
  if (!(max_value > 0.0)) return -1;
  const int bins = static_cast<int>(std::ceil(max_value * kHistogramBinsPerPx)) + 1;
  images->histogram.assign(static_cast<std::size_t>(bins), 0);
  int filtered_count = 0;
  for (int v = 0; v < filtered_region.rows; ++v) {
    const float* row = filtered_region.ptr<float>(v);
    for (int u = 0; u < filtered_region.cols; ++u) {
      if (row[u] > 0.0f) {
        ++images->histogram[static_cast<std::size_t>(row[u] * kHistogramBinsPerPx)];
        ++filtered_count;
      }
    }
  }
  return filtered_count;
}

// Stage 2, valid disparity: enough valid disparities in the region, before and after the filter.
StageOutcome validDisparity(const cv::Mat& disparity, const StereoGeometry& geometry, double search_min_px,
                            double search_max_px, const DetectorParams& p, const RigLimits& limits,
                            SearchImages* images, Detection* result) {
  const int needed = p.closest_min_pixels;
  result->valid_pixels = keepValidDisparities(disparity, geometry, search_min_px, search_max_px, p, limits, images);
  if (result->valid_pixels < needed) {
    result->reason = "only " + std::to_string(result->valid_pixels) +
                     " valid disparity pixels in the region of interest (need " + std::to_string(needed) + ")";
    return ValidDisparityOutcome::kTooFewValid;
  }
  const int filtered_count = filterAndCount(p, images);
  if (filtered_count < 0) {
    result->reason = "no valid disparity left after filtering";
    return ValidDisparityOutcome::kTooFewAfterFilter;
  }
  if (filtered_count < needed) {
    result->reason = "only " + std::to_string(filtered_count) + " valid disparity pixels after filtering (need " +
                     std::to_string(needed) + ")";
    return ValidDisparityOutcome::kTooFewAfterFilter;
  }
  return ValidDisparityOutcome::kPassed;
}

// The closest object: walk the histogram down from the largest disparity until closest_min_pixels pixels are
// collected (a percentile defined by a pixel count, so it does not depend on how much of the scene happens
// to be valid). Negative when fewer are left.
double closestDisparity(const std::vector<int>& histogram, int min_pixels) {
  int collected = 0;
  int closest_bin = static_cast<int>(histogram.size()) - 1;
  for (; closest_bin > 0; --closest_bin) {
    collected += histogram[static_cast<std::size_t>(closest_bin)];
    if (collected >= min_pixels) break;
  }
  if (collected < min_pixels) return -1.0;
  return closest_bin / kHistogramBinsPerPx;
}

// A blob of the band whose size and thickness a target can have, judged by the shape check: its misfit (empty:
// it may be the target), replaced by a part of it when it crosses the tracking window's edge or is larger
// than the mockup (the split). Returns whether, failing, it may be the target degraded (glare, blur): within
// the mockup's upper bounds and at its height, not cut by the border, and not a strip (at least
// degraded_min_width_fraction of its edge-on width wide); then nothing behind it is trusted.
bool shapeCheck(const BandContext& c, const SearchImages& images, double threshold, BlobCandidate* candidate,
                Detection* result) {
  const DetectorParams& p = c.p;
  const StereoGeometry& g = c.geometry;
  candidate->shape = measureBlobShape(*candidate, images.clean, g);
  const auto split = [&]() {
    return p.split_depth_step_m > 0.0
               ? splitMergedBlob(*candidate, images.filtered, images.clean, g, c.bounds, p, c.limits, images.region,
                                 threshold)
               : BlobCandidate();
  };
  if (crossesWindowEdge(candidate->box, images.region, kBorderMarginPx, c.window, c.image_size)) {
    // The window is centred on the tracked target with room around it: what crosses its edge is a
    // neighbour, or the target merged with one (look inside it), never the target cut by the border.
    BlobCandidate part = split();
    if (!part.valid) {
      candidate->misfit = "crosses the tracking window's edge";
      return false;
    }
    *candidate = std::move(part);
    ++result->merged_blobs_split;
  }
  const bool cut = touchesBorder(candidate->box, images.region, kBorderMarginPx);
  candidate->misfit = shapeMismatch(candidate->shape, c.bounds, c.limits, g.focal_px, cut);
  const bool within_upper_bounds =
      shapeMismatch(candidate->shape, c.bounds, c.limits, g.focal_px, /*cut=*/true).empty();
  const std::string height_misfit = heightMismatch(candidatePosition(*candidate, g), p, c.limits);
  const bool degraded = !candidate->misfit.empty() && !cut &&
                        candidate->shape.width_m >= p.degraded_min_width_fraction * c.bounds.min_width_m &&
                        within_upper_bounds && height_misfit.empty();
  if (candidate->misfit.empty() && !cut) candidate->misfit = height_misfit;
  // Larger than the mockup: maybe the target merged with its neighbours; look for it inside.
  if (p.split_depth_step_m > 0.0 && !cut && !candidate->misfit.empty() && !within_upper_bounds) {
    BlobCandidate part = split();
    if (part.valid) {
      *candidate = std::move(part);
      ++result->merged_blobs_split;
    }
  }
  return degraded;
}

// One blob of a band (largest first): too small, not target-shaped, the target, or target-shaped outside the
// hint's gate (a fallback). Returns true when it is the target (the band's search ends).
bool judgeBlob(const BandContext& c, const SearchImages& images, double threshold, BlobCandidate candidate,
               BandSearchState* state, Detection* result) {
  const DetectorParams& p = c.p;
  if (candidate.area < p.min_blob_area_px || candidate.thickness_px < p.min_blob_thickness_px) {
    if (!state->largest_small.valid || candidate.area > state->largest_small.area) {
      state->largest_small = std::move(candidate);
    }
    return false;
  }
  if (!p.shape_check_enabled) {
    state->chosen = std::move(candidate);
    return true;
  }
  const bool degraded = shapeCheck(c, images, threshold, &candidate, result);
  if (!candidate.misfit.empty()) {
    ++result->not_target_shaped_skipped;
    if (degraded && p.stop_behind_target_sized) {
      if (!state->stop_here) {
        candidate.misfit += "; within the mockup's size, so not looked behind";
        state->first_misfit = std::move(candidate);
      }
      state->stop_here = true;
    } else if (!state->first_misfit.valid) {
      state->first_misfit = std::move(candidate);
    }
    return false;
  }
  if (!c.hint.valid || (candidatePosition(candidate, c.geometry) - c.hint.position_m).norm() <= c.hint.radius_m) {
    state->chosen = std::move(candidate);
    return true;
  }
  if (!state->fallback.valid) state->fallback = std::move(candidate);
  return false;
}

// Removes the band (every pixel above `mask`) from the filtered image and its histogram, so the search looks
// behind it; returns how many pixels it held.
int removeBand(const cv::Mat& mask, SearchImages* images) {
  if (images->filtered.data == images->clean.data) {  // no filter ran: keep the raw values for the depth
    images->filtered = images->clean.clone();
  }
  const cv::Rect& region = images->region;
  int band_pixels = 0;
  for (int v = 0; v < region.height; ++v) {
    float* row = images->filtered.ptr<float>(region.y + v) + region.x;
    const std::uint8_t* mask_row = mask.ptr<std::uint8_t>(region.y + v) + region.x;
    for (int u = 0; u < region.width; ++u) {
      if (mask_row[u] != 0) {
        --images->histogram[static_cast<std::size_t>(row[u] * kHistogramBinsPerPx)];
        row[u] = 0.0f;
        ++band_pixels;
      }
    }
  }
  return band_pixels;
}

// The blobs of one band, largest first (the paper took the biggest contour), at most kMaxBlobsPerBand.
std::vector<std::vector<cv::Point>> bandBlobs(const cv::Mat& mask) {
  std::vector<std::vector<cv::Point>> contours;
  cv::findContours(mask, contours, cv::RETR_EXTERNAL, cv::CHAIN_APPROX_SIMPLE);
  std::vector<std::pair<double, std::size_t>> by_area;
  for (std::size_t i = 0; i < contours.size(); ++i) {
    by_area.emplace_back(cv::contourArea(contours[i]) + contours[i].size(), i);
  }
  std::sort(by_area.begin(), by_area.end(), std::greater<>());
  if (by_area.size() > kMaxBlobsPerBand) by_area.resize(kMaxBlobsPerBand);
  std::vector<std::vector<cv::Point>> largest;
  for (const auto& entry : by_area) largest.push_back(std::move(contours[entry.second]));
  return largest;
}

// The blob to report once the search ends: the target; else a target-shaped blob outside the hint (the
// tracker decides); else the first blob that was not target-shaped, or the largest too-small one (reasons).
StageOutcome reportBlob(const DetectorParams& p, BandSearchState* state, BlobCandidate* blob, Detection* result) {
  if (!state->chosen.valid && state->fallback.valid) {
    state->chosen = std::move(state->fallback);
    result->outside_hint = true;
  }
  if (state->chosen.valid) {
    *blob = std::move(state->chosen);
    return BandSearchOutcome::kPassed;
  }
  if (state->first_misfit.valid) {
    result->reason = "not the target: " + state->first_misfit.misfit;
    *blob = std::move(state->first_misfit);
    return BandSearchOutcome::kNotTargetShaped;
  }
  result->reason = "blob too small: every object in view is smaller than min_blob_area_px " +
                   std::to_string(p.min_blob_area_px) + " or thinner than min_blob_thickness_px " +
                   formatNumber(p.min_blob_thickness_px) + " (largest " +
                   std::to_string(std::max(state->largest_skipped_area, state->largest_small.area)) + " px)";
  *blob = std::move(state->largest_small);  // for the debug image, when there is one
  return BandSearchOutcome::kAllBlobsTooSmall;
}

// Stage 3, band search: the closest object, a threshold just below it that keeps the target's own depth
// (RigLimits::band_depth_m behind its nearest point, at least kThresholdMarginPx), and the band's blobs judged;
// without the target in it, the band is removed and the search looks behind it (mismatches at occlusion
// edges, speckles, a wall, a person, furniture), at most kMaxNearObjectsSkipped times. `blob`: the blob to
// report (invalid: none).
StageOutcome searchBands(const BandContext& c, SearchImages* images, BlobCandidate* blob, Detection* result) {
  const DetectorParams& p = c.p;
  cv::Mat mask(c.image_size, CV_8UC1);
  BandSearchState state;
  for (;;) {
    const double closest = closestDisparity(images->histogram, p.closest_min_pixels);
    if (closest < 0.0) break;  // only after skipping: nothing left behind
    result->closest_disparity_px = closest;
    const double threshold = std::max(
        std::min(closest - kThresholdMarginPx, disparityBehind(c.geometry, closest, c.limits.band_depth_m)),
        1.0 / kHistogramBinsPerPx);
    result->threshold_disparity_px = threshold;
    mask.setTo(cv::Scalar(0));
    cv::Mat mask_region = mask(images->region);
    cv::compare(images->filtered(images->region), threshold, mask_region, cv::CMP_GE);  // writes into `mask`
    const auto blobs = bandBlobs(mask);
    if (blobs.empty() && result->near_objects_skipped == 0) {
      result->reason = "no blob above the threshold disparity " + formatNumber(threshold) + " px";
      return BandSearchOutcome::kNoBlob;
    }
    for (const auto& contour : blobs) {
      if (judgeBlob(c, *images, threshold, makeCandidate(contour, mask), &state, result)) break;
    }
    if (state.chosen.valid || state.stop_here || result->near_objects_skipped >= kMaxNearObjectsSkipped) break;
    state.largest_skipped_area = std::max(state.largest_skipped_area, removeBand(mask, images));
    ++result->near_objects_skipped;
  }
  return reportBlob(p, &state, blob, result);
}

// The blob's measured (unfiltered) disparities and their pixels: the median filter chose the pixels, the raw
// values give the depth, so the filter cannot bias it.
void blobDisparities(const Detection& result, const cv::Mat& clean, std::vector<float>* disparities,
                     std::vector<cv::Point>* points) {
  const cv::Rect& box = result.bounding_box;
  for (int v = box.y; v < box.y + box.height; ++v) {
    const std::uint8_t* blob_row = result.mask.ptr<std::uint8_t>(v);
    const float* clean_row = clean.ptr<float>(v);
    for (int u = box.x; u < box.x + box.width; ++u) {
      if (blob_row[u] != 0 && clean_row[u] > 0.0f) {
        disparities->push_back(clean_row[u]);
        points->emplace_back(u, v);
      }
    }
  }
}

// The visible face: the blob's nearest depth layer (the panels and body sides lie behind it). Its centroid
// and median disparity are the centre and robust disparity.
void nearestLayer(const std::vector<float>& disparities, const std::vector<cv::Point>& points,
                  const StereoGeometry& geometry, Detection* result) {
  std::vector<float> sorted = disparities;
  const double reference = percentile(&sorted, kFacePercentile);
  const double band =
      std::max(kFaceMinBandPx, reference - disparityBehind(geometry, reference, kFaceDepthBandM));
  const float face_min = static_cast<float>(reference - band);
  std::vector<float> face_disparities;
  double sum_u = 0.0, sum_v = 0.0;
  for (std::size_t i = 0; i < disparities.size(); ++i) {
    if (disparities[i] >= face_min) {
      face_disparities.push_back(disparities[i]);
      sum_u += points[i].x;
      sum_v += points[i].y;
    }
  }
  result->face_pixels = static_cast<int>(face_disparities.size());
  const double face_count = static_cast<double>(face_disparities.size());
  result->centre_px = cv::Point2d(sum_u / face_count, sum_v / face_count);
  result->disparity_px = median(&face_disparities);
}

// Stage 4, port: the port read off the mockup's footprint fitted to the blob (footprint_fit_enabled; else the
// nearest layer's centre), reprojected with its covariance. `reason`: why no port could be placed.
StageOutcome placePort(const cv::Mat& clean, const StereoGeometry& geometry, const DetectorParams& p,
                       const TargetShape& shape, int blob_area, Detection* result, std::string* reason) {
  std::vector<float> disparities;
  std::vector<cv::Point> points;
  disparities.reserve(static_cast<std::size_t>(blob_area));
  points.reserve(static_cast<std::size_t>(blob_area));
  blobDisparities(*result, clean, &disparities, &points);
  result->blob_pixels = static_cast<int>(disparities.size());
  if (disparities.empty()) return PortOutcome::kPassed;  // plausibility refuses the blob (no pixels)
  nearestLayer(disparities, points, geometry, result);
  StageOutcome outcome = PortOutcome::kPassed;
  if (p.footprint_fit_enabled) outcome = portFromFootprint(points, disparities, geometry, shape, result, reason);
  reproject(geometry, result->centre_px, result->disparity_px, kCentreSigmaPx, kDisparitySigmaPx,
            &result->position_m, &result->covariance_m2);
  // The estimate stands for the port, but the blob's centre is where the visible parts of the mockup are:
  // it moves with the target's yaw (a box side, a panel) by centimetres at any range.
  result->covariance_m2 += Eigen::Matrix3d::Identity() * (p.port_offset_sigma_m * p.port_offset_sigma_m);
  result->range_m = result->position_m.norm();
  return outcome;
}

// Stage 5, plausibility: the blob's size, border and disparity range, with the numbers in the reason so a
// user can tune live.
StageOutcome checkPlausibility(const cv::Rect& region, const DetectorParams& p, const Detection& result,
                               std::string* reason) {
  const cv::Rect& box = result.bounding_box;
  const int margin = kBorderMarginPx;
  const bool left = box.x <= region.x + margin, right = box.x + box.width >= region.x + region.width - margin;
  const bool top = box.y <= region.y + margin, bottom = box.y + box.height >= region.y + region.height - margin;
  if (result.blob_pixels < p.min_blob_area_px) {
    *reason = "blob too small: " + std::to_string(result.blob_pixels) + " px < min_blob_area_px " +
              std::to_string(p.min_blob_area_px);
    return PlausibilityOutcome::kBlobTooSmall;
  }
  if (result.blob_thickness_px < p.min_blob_thickness_px) {
    *reason = "blob too thin: " + formatNumber(result.blob_thickness_px) + " px < min_blob_thickness_px " +
              formatNumber(p.min_blob_thickness_px);
    return PlausibilityOutcome::kBlobTooThin;
  }
  if (p.reject_cut_blobs && (left || right || top || bottom)) {
    *reason = std::string("blob touches the border of the valid region:") + (left ? " left" : "") +
              (right ? " right" : "") + (top ? " top" : "") + (bottom ? " bottom" : "");
    return PlausibilityOutcome::kBlobTouchesBorder;
  }
  if (result.disparity_px < p.min_disparity_px || result.disparity_px > p.max_disparity_px) {
    *reason = "blob disparity " + formatNumber(result.disparity_px) + " px outside [" +
              formatNumber(p.min_disparity_px) + ", " + formatNumber(p.max_disparity_px) + "]";
    return PlausibilityOutcome::kDisparityOutOfRange;
  }
  return PlausibilityOutcome::kPassed;
}

}  // namespace

Detection DisparityDetector::detect(const cv::Mat& disparity, const StereoGeometry& geometry,
                                    double search_min_px, double search_max_px, cv::Rect valid_region,
                                    const SearchHint& hint, const ImageWindow& window) const {
  Detection result;
  SearchImages images;
  result.outcome = selectRegion(disparity, geometry, valid_region, &images.region, &result.reason);
  if (!result.outcome.passed()) return result;
  result.outcome =
      validDisparity(disparity, geometry, search_min_px, search_max_px, params_, limits_, &images, &result);
  if (!result.outcome.passed()) return result;
  const ShapeBounds bounds = shapeBounds(shape_);
  const BandContext context{params_, limits_, geometry, bounds, hint, window, disparity.size()};
  BlobCandidate blob;
  result.outcome = searchBands(context, &images, &blob, &result);
  if (blob.valid) adoptBlob(blob, disparity.size(), &result);
  if (result.outcome == StageOutcome(BandSearchOutcome::kNoBlob) ||
      result.outcome == StageOutcome(BandSearchOutcome::kAllBlobsTooSmall)) {
    return result;
  }
  // A blob not target-shaped is still placed (its centre in the debug image); the search's outcome decides.
  std::string port_reason, plausibility_reason;
  const StageOutcome port = placePort(images.clean, geometry, params_, shape_, blob.area, &result, &port_reason);
  const StageOutcome plausible = checkPlausibility(images.region, params_, result, &plausibility_reason);
  if (!result.outcome.passed()) return result;
  result.outcome = !port.passed() ? port : plausible;
  result.reason = !port.passed() ? "not the target: " + port_reason : plausibility_reason;
  result.found = result.outcome.passed();
  return result;
}

cv::Mat renderDebugImage(const cv::Mat& disparity, const Detection& detection,
                         double display_max_disparity_px) {
  if (disparity.empty() || disparity.type() != CV_32FC1) {
    cv::Mat blank(480, 640, CV_8UC3, cv::Scalar(0, 0, 0));
    drawCaption(blank, detection.reason.empty() ? "no disparity image" : detection.reason, cv::Scalar(0, 0, 255));
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
  if (detection.found) {
    text.precision(2);
    text << std::fixed << "Z " << detection.position_m.z() << " m  d " << std::setprecision(1)
         << detection.disparity_px << " px";
  } else {
    text << detection.reason;
  }
  drawCaption(image, text.str(), colour);
  return image;
}

}  // namespace disparity
}  // namespace docking_perception
