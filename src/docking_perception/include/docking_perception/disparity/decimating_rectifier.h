// The far stage's rectification at a reduced resolution (issue 15): each camera's grey image is
// area-averaged by an integer factor and rectified straight to 1/factor of its calibrated size.
// Block matching costs pixels x disparities, so half resolution costs a quarter of the pixels over half
// the disparities (one eighth); averaging first, not sampling every second pixel, keeps fine texture
// from aliasing and halves the sensor noise the matcher sees.
//
// Conventions are image_geometry's for a binned camera (sensor_msgs/CameraInfo binning_x/y): the
// reduced projection is the full one with its pixel rows divided by the factor, so a CameraInfo with
// the calibrated K, P and binning = factor describes the output exactly.
#pragma once

#include <string>
#include <vector>

#include <opencv2/core.hpp>

#include "docking_perception/disparity/disparity_detector.h"

namespace docking_perception {
namespace disparity {

// One camera as sensor_msgs/CameraInfo states it, at its calibrated resolution (binning 1).
struct PinholeCalibration {
  cv::Size size;                    // calibrated image size, px
  cv::Matx33d camera_matrix;        // K
  std::vector<double> distortion;   // D (plumb_bob: k1 k2 p1 p2 k3; empty: none)
  cv::Matx33d rectification;        // R
  cv::Matx34d projection;           // P
};

// Why a calibration or factor cannot be used; empty when it can. Checked before construction.
std::vector<std::string> validateDecimation(const PinholeCalibration& calibration, int factor);

class DecimatingRectifier {
 public:
  // Throws std::invalid_argument with validateDecimation's reasons.
  DecimatingRectifier(const PinholeCalibration& calibration, int factor);

  // grey: CV_8UC1 at the calibrated size. Throws std::invalid_argument otherwise.
  void rectify(const cv::Mat& grey, cv::Mat* rectified) const;
  // Only `window` (in output pixels) of the rectified image: the same pixels as rectify()'s output cut
  // to it, at the cost of the window alone (the tracking window, tracking_window.h). Throws
  // std::invalid_argument on a bad image or a window not inside outputSize().
  void rectifyWindow(const cv::Mat& grey, const cv::Rect& window, cv::Mat* rectified) const;

  int factor() const { return factor_; }
  cv::Size outputSize() const { return output_size_; }
  // The projection of the output image (the full one's pixel rows / factor).
  cv::Matx34d outputProjection() const;

 private:
  PinholeCalibration calibration_;
  int factor_;
  cv::Size output_size_;
  cv::Mat map_fixed_, map_fraction_;  // cv::remap's fixed-point maps (image_proc's kind), output size
};

// The detector's pixel settings, given at the camera's calibrated resolution (config/disparity_detector.yaml),
// for a disparity image 1/factor of that size: lengths / factor, areas / factor^2 (matcher noise, in px,
// scales as a length); for factor > 1 the blob's minimum area and thickness are the reduced_* ones.
DetectorParams detectorParamsAtDecimation(DetectorParams params, int factor);

}  // namespace disparity
}  // namespace docking_perception
