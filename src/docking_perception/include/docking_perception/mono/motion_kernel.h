// Linear motion blur as a convolution kernel: what a camera that turns or drives during its exposure does
// to the image (issue 11). mono_pose smears its model with it along the rows (robots on a floor yaw and
// drive, so their images smear along the rows); the stress harness blurs its images with it.
#pragma once

#include <opencv2/core.hpp>

namespace docking_perception {
namespace mono {

// A line `length_px` long (pixel centres at its ends) at `angle_rad` from the image rows, anti-aliased,
// normalised to sum 1, centred in an odd square (filter2D's default anchor is the line's midpoint).
cv::Mat linearMotionKernel(double length_px, double angle_rad);

}  // namespace mono
}  // namespace docking_perception
