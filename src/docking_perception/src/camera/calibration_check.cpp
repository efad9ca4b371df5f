#include <docking_perception/camera/calibration_check.h>

namespace docking_perception {
namespace camera {

std::string calibrationFileFromUrl(const std::string& url) {
  const std::string scheme = "file://";
  if (url.rfind(scheme, 0) == 0) return url.substr(scheme.size());
  return url;
}

std::string calibrationSizeProblem(const std::string& calibration_file, int calib_width, int calib_height,
                                   int frame_width, int frame_height, const std::string& frame_origin) {
  // camera_info_manager reports 0x0 when it has no calibration: nothing to compare.
  if (calib_width == 0 && calib_height == 0) return "";
  if (calib_width == frame_width && calib_height == frame_height) return "";
  return "calibration " + calibration_file + " is for " + std::to_string(calib_width) + "x" +
         std::to_string(calib_height) + " images but " + frame_origin + " are " + std::to_string(frame_width) +
         "x" + std::to_string(frame_height) + ": not publishing (recalibrate or fix the resolution)";
}

}  // namespace camera
}  // namespace docking_perception
