#include "docking_perception/mono/motion_kernel.h"

#include <algorithm>
#include <cmath>

namespace docking_perception {
namespace mono {

cv::Mat linearMotionKernel(double length_px, double angle_rad) {
  const int size = static_cast<int>(std::ceil(length_px)) | 1;
  cv::Mat kernel = cv::Mat::zeros(size + 2, size + 2, CV_32F);
  const double centre = 0.5 * (size + 1);
  // Samples along the line, each splatted bilinearly on its four pixels.
  const int steps = std::max(2, static_cast<int>(length_px * 8));
  for (int i = 0; i < steps; ++i) {
    const double s = (static_cast<double>(i) / (steps - 1) - 0.5) * (length_px - 1.0);
    const double x = centre + s * std::cos(angle_rad);
    const double y = centre + s * std::sin(angle_rad);
    const int x0 = static_cast<int>(std::floor(x));
    const int y0 = static_cast<int>(std::floor(y));
    const double fx = x - x0;
    const double fy = y - y0;
    kernel.at<float>(y0, x0) += static_cast<float>((1 - fx) * (1 - fy));
    kernel.at<float>(y0, x0 + 1) += static_cast<float>(fx * (1 - fy));
    kernel.at<float>(y0 + 1, x0) += static_cast<float>((1 - fx) * fy);
    kernel.at<float>(y0 + 1, x0 + 1) += static_cast<float>(fx * fy);
  }
  return kernel / cv::sum(kernel)[0];
}

}  // namespace mono
}  // namespace docking_perception
