// A rendered evaluation sequence as `sim_render --sequence` writes it (docking_sim): a folder of
// rectified grey frames and sequence.json with the rectified intrinsics and, per frame, the stamp, the
// true pose of the docking port in the rectified optical frame and its velocity in that frame.
// Read with yaml-cpp (JSON is YAML's flow style). ROS-free.
#pragma once

#include <Eigen/Core>
#include <stdexcept>
#include <string>
#include <vector>

#include "docking_perception/mono/pose_types.h"

namespace docking_perception {
namespace compare {

struct SequenceFrame {
  int index = 0;
  double stamp_s = 0.0;
  std::string image_path;                            // folder + "/" + the file named in the JSON
  Eigen::Matrix3d rotation = Eigen::Matrix3d::Identity();  // camera <- target
  Eigen::Vector3d position_m = Eigen::Vector3d::Zero();    // target origin in the camera frame
  Eigen::Vector3d linear_m_s = Eigen::Vector3d::Zero();    // d/dt of position_m
  Eigen::Vector3d angular_rad_s = Eigen::Vector3d::Zero(); // target minus camera, camera axes
};

struct Sequence {
  std::string folder;
  std::string scenario;
  std::string target;
  std::string rectification;
  mono::CameraIntrinsics camera;
  double dt_s = 0.0;
  std::vector<SequenceFrame> frames;
};

class SequenceError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

// Reads FOLDER/sequence.json. Throws SequenceError naming the file and the field.
Sequence readSequence(const std::string& folder);

// Largest difference between the true poses of two sequences (position m, rotation rad) and whether
// their stamps agree: two renderings of the same scenario with different targets must match.
bool sameTrajectory(const Sequence& a, const Sequence& b, double tolerance_m, double tolerance_rad,
                    std::string* reason);

}  // namespace compare
}  // namespace docking_perception
