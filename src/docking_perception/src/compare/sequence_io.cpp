#include "sequence_io.h"

#include <yaml-cpp/yaml.h>

#include <cmath>

namespace docking_perception {
namespace compare {
namespace {

[[noreturn]] void fail(const std::string& file, const std::string& field, const std::string& what) {
  throw SequenceError(file + ": " + field + ": " + what);
}

double number(const YAML::Node& parent, const std::string& key, const std::string& file, const std::string& path) {
  const YAML::Node node = parent[key];
  if (!node) fail(file, path + key, "missing");
  try {
    const double v = node.as<double>();
    if (!std::isfinite(v)) fail(file, path + key, "must be finite");
    return v;
  } catch (const YAML::Exception&) {
    fail(file, path + key, "not a number");
  }
}

std::string text(const YAML::Node& parent, const std::string& key, const std::string& file) {
  const YAML::Node node = parent[key];
  if (!node) return "";
  try {
    return node.as<std::string>();
  } catch (const YAML::Exception&) {
    fail(file, key, "not a string");
  }
}

template <int N>
Eigen::Matrix<double, N, 1> vector(const YAML::Node& parent, const std::string& key, const std::string& file,
                                   const std::string& path) {
  const YAML::Node node = parent[key];
  if (!node || !node.IsSequence() || node.size() != N) fail(file, path + key, "must be a list of " + std::to_string(N) + " numbers");
  Eigen::Matrix<double, N, 1> v;
  for (int i = 0; i < N; ++i) {
    try {
      v(i) = node[static_cast<std::size_t>(i)].as<double>();
    } catch (const YAML::Exception&) {
      fail(file, path + key, "must be a list of " + std::to_string(N) + " numbers");
    }
    if (!std::isfinite(v(i))) fail(file, path + key, "must be finite");
  }
  return v;
}

}  // namespace

Sequence readSequence(const std::string& folder) {
  const std::string file = folder + "/sequence.json";
  YAML::Node root;
  try {
    root = YAML::LoadFile(file);
  } catch (const YAML::BadFile&) {
    throw SequenceError(file + ": cannot read the file");
  } catch (const YAML::Exception& e) {
    throw SequenceError(file + ": not valid JSON: " + e.what());
  }
  Sequence seq;
  seq.folder = folder;
  seq.scenario = text(root, "scenario", file);
  seq.target = text(root, "target", file);
  seq.rectification = text(root, "rectification", file);
  const YAML::Node intr = root["intrinsics"];
  if (!intr || !intr.IsMap()) fail(file, "intrinsics", "missing");
  seq.camera.fx = number(intr, "fx", file, "intrinsics.");
  seq.camera.fy = number(intr, "fy", file, "intrinsics.");
  seq.camera.cx = number(intr, "cx", file, "intrinsics.");
  seq.camera.cy = number(intr, "cy", file, "intrinsics.");
  seq.camera.width = static_cast<int>(number(intr, "width", file, "intrinsics."));
  seq.camera.height = static_cast<int>(number(intr, "height", file, "intrinsics."));
  std::string reason;
  if (!seq.camera.isValid(&reason)) fail(file, "intrinsics", reason);
  seq.dt_s = root["dt_s"] ? number(root, "dt_s", file, "") : 0.0;
  const YAML::Node frames = root["frames"];
  if (!frames || !frames.IsSequence() || frames.size() == 0) fail(file, "frames", "missing or empty");
  for (std::size_t i = 0; i < frames.size(); ++i) {
    const YAML::Node f = frames[i];
    const std::string path = "frames[" + std::to_string(i) + "].";
    SequenceFrame frame;
    frame.index = static_cast<int>(i);
    frame.stamp_s = number(f, "stamp_s", file, path);
    const std::string image = text(f, "image", file);
    if (image.empty()) fail(file, path + "image", "missing");
    frame.image_path = image[0] == '/' ? image : folder + "/" + image;
    const Eigen::Matrix<double, 9, 1> r = vector<9>(f, "rotation", file, path);
    for (int a = 0; a < 3; ++a)
      for (int b = 0; b < 3; ++b) frame.rotation(a, b) = r(3 * a + b);
    if ((frame.rotation * frame.rotation.transpose() - Eigen::Matrix3d::Identity()).norm() > 1e-6 ||
        frame.rotation.determinant() < 0)
      fail(file, path + "rotation", "not a rotation matrix");
    frame.position_m = vector<3>(f, "position_m", file, path);
    frame.linear_m_s = vector<3>(f, "linear_m_s", file, path);
    frame.angular_rad_s = vector<3>(f, "angular_rad_s", file, path);
    if (!seq.frames.empty() && !(frame.stamp_s > seq.frames.back().stamp_s))
      fail(file, path + "stamp_s", "stamps must increase");
    seq.frames.push_back(frame);
  }
  return seq;
}

bool sameTrajectory(const Sequence& a, const Sequence& b, double tolerance_m, double tolerance_rad,
                    std::string* reason) {
  if (a.frames.size() != b.frames.size()) {
    *reason = "different frame counts (" + std::to_string(a.frames.size()) + ", " + std::to_string(b.frames.size()) + ")";
    return false;
  }
  for (std::size_t i = 0; i < a.frames.size(); ++i) {
    const SequenceFrame& fa = a.frames[i];
    const SequenceFrame& fb = b.frames[i];
    if (std::abs(fa.stamp_s - fb.stamp_s) > 1e-9 || (fa.position_m - fb.position_m).norm() > tolerance_m ||
        mono::rotationAngleBetween(fa.rotation, fb.rotation) > tolerance_rad) {
      *reason = "frame " + std::to_string(i) + " differs in stamp or true pose";
      return false;
    }
  }
  return true;
}

}  // namespace compare
}  // namespace docking_perception
