// The far stage's tracking window (issue 15; ROS-free): while the target is tracked, block matching runs
// at full resolution only on a window of the rectified pair around where the target is predicted, not on
// the whole 640x480 image. Block matching costs pixels x disparities and the target at 2-6 m covers a
// small part of the image, so the window cuts the far stage's work several times without coarsening the
// depth (the reduced pair's problem, docs/PERFORMANCE.md), and keeps objects far beside the target out of
// the search.
//
// The window covers the mockup's extent around the predicted port (half_width_m, half_height_m, at least
// kWindowMinHalfSizePx), plus what the matcher needs to give those pixels a disparity: on the left the search
// range (a left pixel at column u matches right pixels down to u - min_disparity - disparity_range + 1)
// and half the correlation window on every side. Both images are cut to the same window, so the pair
// stays rectified (the principal points shift together: image_geometry's region of interest).
#pragma once

#include <optional>
#include <string>
#include <vector>

#include <Eigen/Core>
#include <opencv2/core.hpp>

#include "docking_perception/disparity/far_stereo_settings.h"

namespace docking_perception {
namespace disparity {

// TrackingWindowParams (window_* settings) are declared in settings/far_stereo_rectify.yaml (generated header).

// Constants of the window: never narrower than this
// either side of the port (the mockup's 0.9 m span is 45 px wide at 11 m); the fused velocity is extrapolated
// at most this long (about four pairs at 7.5 Hz); a window larger than this share of the image is the whole
// image instead (nearer than ~2 m, where a window saves little).
constexpr int kWindowMinHalfSizePx = 48;
constexpr double kMaxPredictionS = 0.5;
constexpr double kMaxWindowAreaFraction = 0.7;

// What the block matcher needs around a pixel to give it a disparity (config/stereo_image_proc.yaml).
struct MatcherReach {
  int min_disparity = 0;
  int disparity_range = 96;
  int correlation_window_px = 15;
};

// Every invalid field (a range that is not a positive multiple of 16, an even or non-positive window).
std::vector<std::string> validateMatcherReach(const MatcherReach& reach);

// Where the port is expected at the image's time: `position_m` (rectified camera frame, at the estimate's
// time) moved by `velocity_mps` for `elapsed_s`, clamped to [0, kMaxPredictionS].
Eigen::Vector3d predictPort(const Eigen::Vector3d& position_m, const Eigen::Vector3d& velocity_mps,
                            double elapsed_s);

// The window of the rectified image (size `image_size`, projection `projection`: the rectified camera's P)
// to block-match for a port at `port_m` (rectified camera frame); nullopt when the whole image should be
// matched instead: the port behind the camera or outside the image, or the window nearly the whole image.
std::optional<cv::Rect> trackingWindow(const cv::Matx34d& projection, const Eigen::Vector3d& port_m,
                                       cv::Size image_size, const MatcherReach& reach,
                                       const TrackingWindowParams& params);

}  // namespace disparity
}  // namespace docking_perception
