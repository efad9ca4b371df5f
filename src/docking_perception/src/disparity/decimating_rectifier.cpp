#include "docking_perception/disparity/decimating_rectifier.h"

#include <algorithm>
#include <cmath>
#include <sstream>
#include <stdexcept>

#include <opencv2/calib3d.hpp>
#include <opencv2/imgproc.hpp>

namespace docking_perception {
namespace disparity {
namespace {

constexpr int kMaxFactor = 4;  // beyond a quarter the face at 6 m is a handful of pixels

std::string joined(const std::vector<std::string>& reasons) {
  std::ostringstream text;
  for (std::size_t i = 0; i < reasons.size(); ++i) text << (i ? "; " : "") << reasons[i];
  return text.str();
}

// The camera matrix of the area-averaged raw image: output pixel i averages input pixels
// [f i, f i + f - 1], whose centre is f i + (f - 1) / 2 in input pixels.
cv::Matx33d averagedCameraMatrix(const cv::Matx33d& k, int factor) {
  cv::Matx33d out = k;
  for (int row = 0; row < 2; ++row) {
    out(row, 0) /= factor;
    out(row, 1) /= factor;
    out(row, 2) = (k(row, 2) - 0.5 * (factor - 1)) / factor;
  }
  return out;
}

// image_geometry's reduced projection for binning = factor: the pixel rows divided by it.
cv::Matx34d reducedProjection(const cv::Matx34d& p, int factor) {
  cv::Matx34d out = p;
  for (int row = 0; row < 2; ++row) {
    for (int col = 0; col < 4; ++col) out(row, col) /= factor;
  }
  return out;
}

}  // namespace

std::vector<std::string> validateDecimation(const PinholeCalibration& calibration, int factor) {
  std::vector<std::string> reasons;
  if (factor < 1 || factor > kMaxFactor) {
    reasons.push_back("decimation must be 1.." + std::to_string(kMaxFactor) + " (got " +
                      std::to_string(factor) + ")");
    return reasons;
  }
  if (calibration.size.width <= 0 || calibration.size.height <= 0 ||
      calibration.size.width % factor != 0 || calibration.size.height % factor != 0) {
    reasons.push_back("calibrated size " + std::to_string(calibration.size.width) + "x" +
                      std::to_string(calibration.size.height) + " must be positive and divisible by the decimation " +
                      std::to_string(factor));
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

DecimatingRectifier::DecimatingRectifier(const PinholeCalibration& calibration, int factor)
    : calibration_(calibration), factor_(factor) {
  const auto reasons = validateDecimation(calibration, factor);
  if (!reasons.empty()) throw std::invalid_argument("DecimatingRectifier: " + joined(reasons));
  output_size_ = cv::Size(calibration.size.width / factor, calibration.size.height / factor);
  const cv::Mat distortion = calibration.distortion.empty()
                                 ? cv::Mat()
                                 : cv::Mat(calibration.distortion, true).reshape(1, 1);
  cv::initUndistortRectifyMap(averagedCameraMatrix(calibration.camera_matrix, factor), distortion,
                              calibration.rectification, outputProjection(), output_size_, CV_16SC2,
                              map_fixed_, map_fraction_);
}

cv::Matx34d DecimatingRectifier::outputProjection() const {
  return reducedProjection(calibration_.projection, factor_);
}

void DecimatingRectifier::rectify(const cv::Mat& grey, cv::Mat* rectified) const {
  rectifyWindow(grey, cv::Rect(cv::Point(0, 0), output_size_), rectified);
}

void DecimatingRectifier::rectifyWindow(const cv::Mat& grey, const cv::Rect& window, cv::Mat* rectified) const {
  if (window.area() <= 0 || (window & cv::Rect(cv::Point(0, 0), output_size_)) != window) {
    std::ostringstream problem;
    problem << "DecimatingRectifier: window " << window.width << "x" << window.height << " at (" << window.x
            << ", " << window.y << ") is not inside the " << output_size_.width << "x" << output_size_.height
            << " output";
    throw std::invalid_argument(problem.str());
  }
  if (grey.type() != CV_8UC1 || grey.size() != calibration_.size) {
    std::ostringstream problem;
    problem << "DecimatingRectifier: expected an 8-bit grey image of " << calibration_.size.width << "x"
            << calibration_.size.height << ", got type " << grey.type() << " of " << grey.cols << "x"
            << grey.rows;
    throw std::invalid_argument(problem.str());
  }
  cv::Mat averaged = grey;
  if (factor_ > 1) cv::resize(grey, averaged, output_size_, 0.0, 0.0, cv::INTER_AREA);
  // The maps give each output pixel its source point, so their window rectifies the window alone.
  cv::remap(averaged, *rectified, map_fixed_(window), map_fraction_(window), cv::INTER_LINEAR);
}

DetectorParams detectorParamsAtDecimation(DetectorParams params, int factor) {
  if (factor <= 1) return params;
  const double length = 1.0 / factor;
  const auto area = [factor](int px) { return std::max(1, static_cast<int>(std::lround(static_cast<double>(px) / (factor * factor)))); };
  params.closest_min_pixels = area(params.closest_min_pixels);
  params.min_blob_area_px = area(params.reduced_min_blob_area_px);
  params.threshold_margin_px *= length;
  params.face_min_band_px *= length;
  params.min_blob_thickness_px = params.reduced_min_blob_thickness_px * length;
  params.border_margin_px = std::max(1, static_cast<int>(std::lround(params.border_margin_px * length)));
  params.min_disparity_px *= length;
  params.max_disparity_px *= length;
  params.disparity_sigma_px *= length;
  params.centre_sigma_px *= length;
  params.shape_tolerance_px *= length;
  // The reduced pair's depth is too coarse for the footprint fit: near boxes it places the face on the
  // wrong side (far_tracking_still_3m: 0.149 m off at 2.9 m); the nearest layer is used there.
  params.footprint_fit_enabled = false;
  return params;
}

}  // namespace disparity
}  // namespace docking_perception
