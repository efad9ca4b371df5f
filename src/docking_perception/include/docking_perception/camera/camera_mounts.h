// Where the chaser's cameras sit on base_link, read from config/robot.yaml. ROS-free.
#pragma once

#include <Eigen/Geometry>

#include <string>
#include <vector>

namespace docking_perception {
namespace camera {

struct CameraMount {
  std::string name;          // key under chaser.cameras, e.g. "stereo_left"
  std::string frame_id;      // the camera's optical frame
  std::string calibration;   // calibration file as written (relative to the robot file's folder)
  Eigen::Vector3d xyz_m = Eigen::Vector3d::Zero();    // position in the base frame
  Eigen::Vector3d rpy_rad = Eigen::Vector3d::Zero();  // fixed-axis roll, pitch, yaw (as in URDF)
};

struct RobotCameras {
  std::string base_frame;
  std::vector<CameraMount> cameras;  // in file order
};

// Reads chaser.base_frame and chaser.cameras.<name>.{frame_id, xyz_m, rpy_rad, calibration}. Throws
// std::runtime_error naming the file and the field (e.g. "robot.yaml: chaser.cameras.ir.xyz_m: expected
// a list of 3 numbers") for a missing file, bad YAML, a missing or malformed field, a non-finite number,
// an empty or duplicate frame_id.
RobotCameras loadRobotCameras(const std::string& path);

// URDF's rpy: rotate about the fixed x by roll, then fixed y by pitch, then fixed z by yaw
// (R = Rz(yaw) * Ry(pitch) * Rx(roll)).
Eigen::Quaterniond quaternionFromFixedAxisRpy(const Eigen::Vector3d& rpy_rad);

}  // namespace camera
}  // namespace docking_perception
