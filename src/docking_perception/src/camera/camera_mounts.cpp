#include <docking_perception/camera/camera_mounts.h>

#include <yaml-cpp/yaml.h>

#include <cmath>
#include <set>
#include <stdexcept>

namespace docking_perception {
namespace camera {
namespace {

[[noreturn]] void fail(const std::string& path, const std::string& field, const std::string& what) {
  throw std::runtime_error(path + ": " + field + ": " + what);
}

std::string readString(const YAML::Node& node, const std::string& path, const std::string& field) {
  if (!node) fail(path, field, "missing");
  if (!node.IsScalar()) fail(path, field, "expected a string");
  const auto value = node.as<std::string>();
  if (value.empty()) fail(path, field, "must not be empty");
  return value;
}

Eigen::Vector3d readVector3(const YAML::Node& node, const std::string& path, const std::string& field) {
  if (!node) fail(path, field, "missing");
  if (!node.IsSequence() || node.size() != 3) fail(path, field, "expected a list of 3 numbers");
  Eigen::Vector3d value;
  for (size_t i = 0; i < 3; ++i) {
    try {
      value[static_cast<Eigen::Index>(i)] = node[i].as<double>();
    } catch (const YAML::Exception&) {
      fail(path, field, "element " + std::to_string(i) + " is not a number");
    }
    if (!std::isfinite(value[static_cast<Eigen::Index>(i)])) {
      fail(path, field, "element " + std::to_string(i) + " is not finite");
    }
  }
  return value;
}

}  // namespace

RobotCameras loadRobotCameras(const std::string& path) {
  YAML::Node root;
  try {
    root = YAML::LoadFile(path);
  } catch (const YAML::BadFile&) {
    throw std::runtime_error(path + ": cannot open the robot file");
  } catch (const YAML::Exception& e) {
    throw std::runtime_error(path + ": invalid YAML: " + e.what());
  }
  const YAML::Node chaser = root["chaser"];
  if (!chaser || !chaser.IsMap()) fail(path, "chaser", "missing (expected a map)");

  RobotCameras robot;
  robot.base_frame = readString(chaser["base_frame"], path, "chaser.base_frame");

  const YAML::Node cameras = chaser["cameras"];
  if (!cameras || !cameras.IsMap() || cameras.size() == 0) {
    fail(path, "chaser.cameras", "missing (expected a map of cameras)");
  }
  std::set<std::string> frame_ids;
  for (const auto& entry : cameras) {
    CameraMount mount;
    mount.name = entry.first.as<std::string>();
    const std::string field = "chaser.cameras." + mount.name;
    const YAML::Node& camera = entry.second;
    if (!camera.IsMap()) fail(path, field, "expected a map");
    mount.frame_id = readString(camera["frame_id"], path, field + ".frame_id");
    if (mount.frame_id == robot.base_frame) fail(path, field + ".frame_id", "equals the base frame");
    if (!frame_ids.insert(mount.frame_id).second) {
      fail(path, field + ".frame_id", "'" + mount.frame_id + "' is used by another camera");
    }
    if (camera["calibration"]) mount.calibration = readString(camera["calibration"], path, field + ".calibration");
    mount.xyz_m = readVector3(camera["xyz_m"], path, field + ".xyz_m");
    mount.rpy_rad = readVector3(camera["rpy_rad"], path, field + ".rpy_rad");
    robot.cameras.push_back(mount);
  }
  return robot;
}

Eigen::Quaterniond quaternionFromFixedAxisRpy(const Eigen::Vector3d& rpy_rad) {
  const Eigen::AngleAxisd roll(rpy_rad.x(), Eigen::Vector3d::UnitX());
  const Eigen::AngleAxisd pitch(rpy_rad.y(), Eigen::Vector3d::UnitY());
  const Eigen::AngleAxisd yaw(rpy_rad.z(), Eigen::Vector3d::UnitZ());
  return (yaw * pitch * roll).normalized();
}

}  // namespace camera
}  // namespace docking_perception
