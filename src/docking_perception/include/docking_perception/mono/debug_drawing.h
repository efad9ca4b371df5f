// The mono_pose debug image, drawn without ROS: all ratio-test matches (grey), the points the pose
// used (green), the matched face outline (yellow), located markers / LED blobs (red / orange), and, for a
// valid pose, the model's face outline projected with that pose (cyan) and the target axes (x red,
// y green, z blue), with the status or the range written on top.
#pragma once

#include <opencv2/core.hpp>

#include "docking_perception/mono/mono_pose_estimator.h"

namespace docking_perception {
namespace mono {

// image: the input (gray or BGR); returns a BGR image of the same size.
cv::Mat drawDebugImage(const cv::Mat& image, const MonoPoseResult& result, const CameraIntrinsics& camera,
                       const TargetModel& model);

}  // namespace mono
}  // namespace docking_perception
