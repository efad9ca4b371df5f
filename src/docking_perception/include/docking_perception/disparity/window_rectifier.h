// The far stage's rectification (issue 15): each camera's grey image rectified with the maps of its
// calibration, the whole image or only a window of it (the tracking window, tracking_window.h), at the cost
// of the window alone. ROS-free.
//
// The calibration is sensor_msgs/CameraInfo's (K, D, R, P at the calibrated size); the output is the
// rectified camera P describes.
#pragma once

#include <string>
#include <vector>

#include <opencv2/core.hpp>

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

// Why a calibration cannot be used; empty when it can. Checked before construction.
std::vector<std::string> validateCalibration(const PinholeCalibration& calibration);

class WindowRectifier {
 public:
  // Throws std::invalid_argument with validateCalibration's reasons.
  explicit WindowRectifier(const PinholeCalibration& calibration);

  // grey: CV_8UC1 at the calibrated size. Throws std::invalid_argument otherwise.
  void rectify(const cv::Mat& grey, cv::Mat* rectified) const;
  // Only `window` of the rectified image: the same pixels as rectify()'s output cut to it, at the cost of
  // the window alone. Throws std::invalid_argument on a bad image or a window not inside outputSize().
  void rectifyWindow(const cv::Mat& grey, const cv::Rect& window, cv::Mat* rectified) const;

  cv::Size outputSize() const { return calibration_.size; }
  // The projection of the output image (the calibration's P).
  cv::Matx34d outputProjection() const { return calibration_.projection; }

 private:
  PinholeCalibration calibration_;
  cv::Mat map_fixed_, map_fraction_;  // cv::remap's fixed-point maps (image_proc's kind), output size
};

}  // namespace disparity
}  // namespace docking_perception
