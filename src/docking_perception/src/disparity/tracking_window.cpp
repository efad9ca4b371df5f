#include "docking_perception/disparity/tracking_window.h"

#include <algorithm>
#include <cmath>

namespace docking_perception {
namespace disparity {

namespace {
constexpr double kMinDepthM = 0.1;  // a port nearer than this (or behind the camera) has no sensible window
}  // namespace

std::vector<std::string> validateMatcherReach(const MatcherReach& reach) {
  std::vector<std::string> errors;
  if (reach.disparity_range <= 0 || reach.disparity_range % 16 != 0) {
    errors.push_back("the matcher's disparity_range must be a positive multiple of 16 (got " +
                     std::to_string(reach.disparity_range) + ")");
  }
  if (reach.correlation_window_px < 1 || reach.correlation_window_px % 2 == 0) {
    errors.push_back("the matcher's correlation_window_size must be odd and positive (got " +
                     std::to_string(reach.correlation_window_px) + ")");
  }
  return errors;
}

Eigen::Vector3d predictPort(const Eigen::Vector3d& position_m, const Eigen::Vector3d& velocity_mps,
                            double elapsed_s) {
  const double dt = std::clamp(elapsed_s, 0.0, kMaxPredictionS);
  return velocity_mps.allFinite() ? Eigen::Vector3d(position_m + velocity_mps * dt) : position_m;
}

std::optional<cv::Rect> trackingWindow(const cv::Matx34d& projection, const Eigen::Vector3d& port_m,
                                       cv::Size image_size, const MatcherReach& reach,
                                       const TrackingWindowParams& params) {
  if (!port_m.allFinite() || port_m.z() < kMinDepthM || image_size.area() <= 0) return std::nullopt;
  const cv::Vec3d h = projection * cv::Vec4d(port_m.x(), port_m.y(), port_m.z(), 1.0);
  if (!(h[2] > 0.0)) return std::nullopt;
  const double u = h[0] / h[2], v = h[1] / h[2];
  if (u < 0.0 || v < 0.0 || u >= image_size.width || v >= image_size.height) return std::nullopt;

  const double half_width_px = std::max<double>(kWindowMinHalfSizePx,
                                                projection(0, 0) * params.half_width_m / port_m.z());
  const double half_height_px = std::max<double>(kWindowMinHalfSizePx,
                                                 projection(1, 1) * params.half_height_m / port_m.z());
  const int half_correlation = reach.correlation_window_px / 2;
  // Left: the search range reaches this far into the right image (the same columns of the window).
  const int left_reach = std::max(0, reach.min_disparity + reach.disparity_range - 1) + half_correlation;
  const int left = static_cast<int>(std::floor(u - half_width_px)) - left_reach;
  const int right = static_cast<int>(std::ceil(u + half_width_px)) + half_correlation + 1;
  const int top = static_cast<int>(std::floor(v - half_height_px)) - half_correlation;
  const int bottom = static_cast<int>(std::ceil(v + half_height_px)) + half_correlation + 1;
  const cv::Rect window = cv::Rect(left, top, right - left, bottom - top) & cv::Rect(cv::Point(0, 0), image_size);
  if (window.area() <= 0 || window.area() > kMaxWindowAreaFraction * image_size.area()) return std::nullopt;
  return window;
}

}  // namespace disparity
}  // namespace docking_perception
