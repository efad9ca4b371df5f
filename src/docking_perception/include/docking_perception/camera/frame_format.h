// Turning a captured OpenCV frame into what the camera publishes (sensor_msgs encodings). ROS-free.
#pragma once

#include <opencv2/core.hpp>
#include <string>

namespace docking_perception {
namespace camera {

enum class ColourMode {
  kKeep,  // colour stays colour (bgr8), grey stays grey (mono8): the visible stereo pair
  kMono,  // everything becomes mono8: the IR camera (the Pi NoIR delivers colour frames)
};

struct PublishableFrame {
  cv::Mat image;         // 8-bit, 1 or 3 channels; shares data with the input when no conversion is needed
  std::string encoding;  // "mono8" or "bgr8" (sensor_msgs/image_encodings names)
  std::string error;     // non-empty: the frame cannot be published, and why
  bool ok() const { return error.empty(); }
};

// Accepts 8-bit frames with 1 (grey), 3 (BGR) or 4 (BGRA) channels; anything else (empty, 16-bit, 2
// channels) gives an error naming its type.
PublishableFrame toPublishable(const cv::Mat& frame, ColourMode mode);

}  // namespace camera
}  // namespace docking_perception
