// A synthetic view of a flat face texture (no simulator): the texture projected by a pinhole camera at
// a known pose, 4x supersampled and area-averaged, on a grey background with seeded noise. For the
// AprilTag test and the benchmark's fallback frame. ROS-free.
#pragma once

#include <Eigen/Geometry>
#include <opencv2/core.hpp>

#include "docking_perception/mono/pose_types.h"

namespace docking_perception {
namespace compare {

// texture: 8-bit grey, covering face_width_m x face_height_m of the plane x = 0 of frame `target`
// (column u along +y, row v along -z). camera_T_target: pose of the face in the optical frame.
cv::Mat renderFaceView(const cv::Mat& texture, double face_width_m, double face_height_m,
                       const mono::CameraIntrinsics& camera, const Eigen::Isometry3d& camera_T_target,
                       double noise_sigma = 2.0, int background = 110, unsigned seed = 1);

}  // namespace compare
}  // namespace docking_perception
