#include "docking_perception/disparity/window_rectifier.h"

#include <cmath>
#include <sstream>
#include <stdexcept>

#include <opencv2/calib3d.hpp>
#include <opencv2/imgproc.hpp>

namespace docking_perception {
namespace disparity {
namespace {

std::string joined(const std::vector<std::string>& reasons) {
  std::ostringstream text;
  for (std::size_t i = 0; i < reasons.size(); ++i) text << (i ? "; " : "") << reasons[i];
  return text.str();
}

}  // namespace

std::vector<std::string> validateCalibration(const PinholeCalibration& calibration) {
  std::vector<std::string> reasons;
  if (calibration.size.width <= 0 || calibration.size.height <= 0) {
    reasons.push_back("calibrated size " + std::to_string(calibration.size.width) + "x" +
                      std::to_string(calibration.size.height) + " must be positive");
  }
  if (!(calibration.camera_matrix(0, 0) > 0.0) || !(calibration.camera_matrix(1, 1) > 0.0)) {
    reasons.push_back("camera matrix K must have positive focal lengths");
  }
  if (!(calibration.projection(0, 0) > 0.0) || !(calibration.projection(1, 1) > 0.0)) {
    reasons.push_back("projection P must have positive focal lengths (is the camera calibrated?)");
  }
  const std::size_t n = calibration.distortion.size();
  if (n != 0 && n != 4 && n != 5 && n != 8) {
    reasons.push_back("distortion must have 0, 4, 5 or 8 coefficients (got " + std::to_string(n) + ")");
  }
  for (double d : calibration.distortion) {
    if (!std::isfinite(d)) reasons.push_back("distortion coefficients must be finite");
  }
  return reasons;
}

WindowRectifier::WindowRectifier(const PinholeCalibration& calibration) : calibration_(calibration) {
  const auto reasons = validateCalibration(calibration);
  if (!reasons.empty()) throw std::invalid_argument("WindowRectifier: " + joined(reasons));
  const cv::Mat distortion = calibration.distortion.empty()
                                 ? cv::Mat()
                                 : cv::Mat(calibration.distortion, true).reshape(1, 1);
  cv::initUndistortRectifyMap(calibration.camera_matrix, distortion, calibration.rectification,
                              calibration.projection, calibration.size, CV_16SC2, map_fixed_, map_fraction_);
}

void WindowRectifier::rectify(const cv::Mat& grey, cv::Mat* rectified) const {
  rectifyWindow(grey, cv::Rect(cv::Point(0, 0), outputSize()), rectified);
}

void WindowRectifier::rectifyWindow(const cv::Mat& grey, const cv::Rect& window, cv::Mat* rectified) const {
  const cv::Size size = outputSize();
  if (window.area() <= 0 || (window & cv::Rect(cv::Point(0, 0), size)) != window) {
    std::ostringstream problem;
    problem << "WindowRectifier: window " << window.width << "x" << window.height << " at (" << window.x << ", "
            << window.y << ") is not inside the " << size.width << "x" << size.height << " output";
    throw std::invalid_argument(problem.str());
  }
  if (grey.type() != CV_8UC1 || grey.size() != size) {
    std::ostringstream problem;
    problem << "WindowRectifier: expected an 8-bit grey image of " << size.width << "x" << size.height
            << ", got type " << grey.type() << " of " << grey.cols << "x" << grey.rows;
    throw std::invalid_argument(problem.str());
  }
  // The maps give each output pixel its source point, so their window rectifies the window alone.
  cv::remap(grey, *rectified, map_fixed_(window), map_fraction_(window), cv::INTER_LINEAR);
}

}  // namespace disparity
}  // namespace docking_perception
