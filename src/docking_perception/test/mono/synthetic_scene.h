// Synthetic targets and camera views for the mono_pose tests and benchmark: a random texture with the
// 5 dark marker dots (each on a white ring, as on the real texture), rendered into a camera view with
// the plane's homography, and IR views with Gaussian LED spots. Everything is seeded: reproducible.
#pragma once

#include <Eigen/Core>
#include <Eigen/Geometry>
#include <opencv2/core.hpp>
#include <vector>

#include "docking_perception/mono/apriltag_pose.h"
#include "docking_perception/mono/pose_types.h"
#include "docking_perception/mono/target_model.h"

namespace docking_perception {
namespace mono {
namespace synthetic {

// The numbers of config/target.yaml (face 0.30 x 0.24 m, markers, radii), so that tests exercise the
// real geometry without reading the file.
MarkerPoints defaultMarkers();
// A 600x480 random texture with the markers printed on it.
cv::Mat makeTexture(uint64_t seed, int cols = 600, int rows = 480);
TargetModel makeModel(uint64_t seed);
// The stereo_left intrinsics: f = 550 px, 640x480.
CameraIntrinsics defaultCamera();

// camera <- target rotation of a target whose face looks straight at the camera, turned by yaw about
// its own z (up) axis, then pitch about its y axis, then roll about its x (normal) axis (rad).
Eigen::Matrix3d facingRotation(double yaw, double pitch = 0.0, double roll = 0.0);

// The face rendered into a gray camera image over a random background, with Gaussian pixel noise; with
// its inner pattern (when the model has one) printed over the texture when `with_inner_pattern`, as on
// the real face and in docking_sim.
cv::Mat renderVisible(const TargetModel& model, const CameraIntrinsics& camera, const Eigen::Matrix3d& rotation,
                      const Eigen::Vector3d& translation, uint64_t seed, double noise_sigma = 2.0,
                      bool with_inner_pattern = false);

// The inner pattern's print (its white ring included, black 25, white 240) drawn over `image` where a
// camera with `camera_T_target` sees it: the print warped by the exact homography of its plane. No blur
// or noise: the caller's image model adds them.
void drawInnerPattern(cv::Mat* image, const TagSpec& tag, const CameraIntrinsics& camera,
                      const Eigen::Isometry3d& camera_T_target);

// IR view: dark noisy background and one Gaussian spot per given point (camera frame), LED radius in m.
cv::Mat renderLedSpots(const CameraIntrinsics& camera, const std::vector<Eigen::Vector3d>& points_camera,
                       double led_radius_m, uint64_t seed);
// Gaussian spots at given pixels with a given sigma (px).
void drawSpot(cv::Mat* image, const Eigen::Vector2d& centre, double sigma_px, double peak);

}  // namespace synthetic
}  // namespace mono
}  // namespace docking_perception
