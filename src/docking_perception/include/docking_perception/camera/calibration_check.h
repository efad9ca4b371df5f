// Checks that a camera calibration fits the images it is published with. ROS-free.
#pragma once

#include <string>

namespace docking_perception {
namespace camera {

// "file:///a/b.yaml" -> "/a/b.yaml"; a URL of another scheme (package://, empty) is returned unchanged,
// so that messages still name what was configured.
std::string calibrationFileFromUrl(const std::string& url);

// Empty when a calibration made for calib_width x calib_height fits frames of frame_width x frame_height
// (or when there is no calibration, calib size 0x0); otherwise a message naming the calibration file,
// both sizes and `frame_origin` (e.g. "the frames of V4L2 device /dev/video0").
std::string calibrationSizeProblem(const std::string& calibration_file, int calib_width, int calib_height,
                                   int frame_width, int frame_height, const std::string& frame_origin);

}  // namespace camera
}  // namespace docking_perception
