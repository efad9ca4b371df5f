#include <docking_perception/camera/frame_format.h>

#include <opencv2/imgproc.hpp>

namespace docking_perception {
namespace camera {

PublishableFrame toPublishable(const cv::Mat& frame, ColourMode mode) {
  PublishableFrame out;
  if (frame.empty()) {
    out.error = "empty frame";
    return out;
  }
  if (frame.depth() != CV_8U || (frame.channels() != 1 && frame.channels() != 3 && frame.channels() != 4)) {
    out.error = "unsupported frame type " + cv::typeToString(frame.type()) +
                " (expected 8-bit grey, BGR or BGRA)";
    return out;
  }
  if (frame.channels() == 1) {
    out.image = frame;
    out.encoding = "mono8";
    return out;
  }
  if (mode == ColourMode::kMono) {
    cv::cvtColor(frame, out.image, frame.channels() == 3 ? cv::COLOR_BGR2GRAY : cv::COLOR_BGRA2GRAY);
    out.encoding = "mono8";
    return out;
  }
  if (frame.channels() == 4) {
    cv::cvtColor(frame, out.image, cv::COLOR_BGRA2BGR);
  } else {
    out.image = frame;
  }
  out.encoding = "bgr8";
  return out;
}

}  // namespace camera
}  // namespace docking_perception
