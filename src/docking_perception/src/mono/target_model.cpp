#include "docking_perception/mono/target_model.h"

#include <yaml-cpp/yaml.h>

#include <Eigen/Geometry>
#include <cmath>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

namespace docking_perception {
namespace mono {
namespace {

constexpr double kPlaneTolerance = 1e-6;

[[noreturn]] void fail(const std::string& source, const std::string& field, const std::string& what) {
  throw TargetModelError(source + ": " + field + ": " + what);
}

YAML::Node requireNode(const YAML::Node& parent, const std::string& key, const std::string& source,
                       const std::string& path) {
  const YAML::Node node = parent[key];
  if (!node) fail(source, path, "missing");
  return node;
}

double requireDouble(const YAML::Node& parent, const std::string& key, const std::string& source,
                     const std::string& path) {
  const YAML::Node node = requireNode(parent, key, source, path);
  try {
    const double value = node.as<double>();
    if (!std::isfinite(value)) fail(source, path, "not a finite number");
    return value;
  } catch (const YAML::Exception&) {
    fail(source, path, "not a number");
  }
}

cv::Mat toGray(const cv::Mat& image) {
  if (image.empty()) return image;
  cv::Mat gray;
  if (image.channels() == 3) {
    cv::cvtColor(image, gray, cv::COLOR_BGR2GRAY);
  } else if (image.channels() == 4) {
    cv::cvtColor(image, gray, cv::COLOR_BGRA2GRAY);
  } else {
    gray = image;
  }
  if (gray.depth() != CV_8U) gray.convertTo(gray, CV_8U);
  return gray.clone();
}

// target.inner_pattern (optional): an AprilTag on the face near the port (the inner pattern).
TagSpec readInnerPattern(const YAML::Node& node, const std::string& src, double face_width, double face_height) {
  const std::string base = "target.inner_pattern";
  if (!node.IsMap()) fail(src, base, "must be a map");
  TagSpec tag;
  try {
    const std::string type = requireNode(node, "type", src, base + ".type").as<std::string>();
    if (type != "apriltag") fail(src, base + ".type", "only 'apriltag' is supported, got '" + type + "'");
    tag.family = requireNode(node, "family", src, base + ".family").as<std::string>();
    tag.id = requireNode(node, "id", src, base + ".id").as<int>();
    const YAML::Node c = requireNode(node, "center_m", src, base + ".center_m");
    if (!c.IsSequence() || c.size() != 3) fail(src, base + ".center_m", "must be [x, y, z]");
    tag.center_m = {c[0].as<double>(), c[1].as<double>(), c[2].as<double>()};
  } catch (const YAML::Exception& e) {
    fail(src, base, e.what());
  }
  tag.size_m = requireDouble(node, "size_m", src, base + ".size_m");
  if (tag.family != "tag36h11") fail(src, base + ".family", "only tag36h11 is supported");
  if (tag.id < 0 || tag.id > 586) fail(src, base + ".id", "must be in [0, 586] for tag36h11");
  if (!(tag.size_m >= 0.005 && tag.size_m <= 1.0)) fail(src, base + ".size_m", "must be in [0.005, 1] m");
  if (std::abs(tag.center_m.x()) > kPlaneTolerance) fail(src, base + ".center_m", "must lie on the face (x = 0)");
  const double half_print = 0.5 * tag.size_m * 10.0 / 8.0;  // tag36h11: 8 of 10 cells inside the white ring
  if (std::abs(tag.center_m.y()) + half_print > 0.5 * face_width + 1e-9 ||
      std::abs(tag.center_m.z()) + half_print > 0.5 * face_height + 1e-9) {
    fail(src, base + ".center_m", "the tag (with its white ring) does not fit on the face");
  }
  return tag;
}

}  // namespace

void TargetModel::validate(const std::string& source, double width, double height, const MarkerPoints& markers,
                           double marker_radius, double led_radius) {
  if (!(width > 0.0)) fail(source, "target.face.width_m", "must be positive");
  if (!(height > 0.0)) fail(source, "target.face.height_m", "must be positive");
  if (!(marker_radius > 0.0)) fail(source, "target.marker_radius_m", "must be positive");
  if (!(led_radius > 0.0)) fail(source, "target.led_radius_m", "must be positive");
  for (int i = 0; i < kMarkerCount; ++i) {
    const std::string field = "target.markers_m[" + std::to_string(i) + "]";
    const Eigen::Vector3d& m = markers[static_cast<size_t>(i)];
    if (std::abs(m.x()) > kPlaneTolerance) fail(source, field, "must lie on the face plane x = 0");
    if (std::abs(m.y()) > 0.5 * width + 1e-9 || std::abs(m.z()) > 0.5 * height + 1e-9) {
      fail(source, field, "lies outside the face");
    }
  }
  // The solver relies on the two midpoint relations and on two non-parallel arms.
  const double tolerance = 1e-6;
  if ((markers[1] - 0.5 * (markers[0] + markers[2])).norm() > tolerance) {
    fail(source, "target.markers_m[1]", "must be the midpoint of markers 0 and 2 (triple A)");
  }
  if ((markers[3] - 0.5 * (markers[2] + markers[4])).norm() > tolerance) {
    fail(source, "target.markers_m[3]", "must be the midpoint of markers 2 and 4 (triple B)");
  }
  const Eigen::Vector3d arm_a = markers[0] - markers[2];
  const Eigen::Vector3d arm_b = markers[4] - markers[2];
  if (arm_a.norm() < 1e-3 || arm_b.norm() < 1e-3) fail(source, "target.markers_m", "arms shorter than 1 mm");
  if (arm_a.normalized().cross(arm_b.normalized()).norm() < std::sin(10.0 * M_PI / 180.0)) {
    fail(source, "target.markers_m", "the two arms (0-2 and 2-4) must be at least 10 degrees apart");
  }
}

TargetModel TargetModel::fromParts(double face_width_m, double face_height_m, const MarkerPoints& markers_m,
                                   double marker_radius_m, double led_radius_m, const cv::Mat& texture) {
  validate("<parts>", face_width_m, face_height_m, markers_m, marker_radius_m, led_radius_m);
  TargetModel model;
  model.face_width_m_ = face_width_m;
  model.face_height_m_ = face_height_m;
  model.markers_m_ = markers_m;
  model.marker_radius_m_ = marker_radius_m;
  model.led_radius_m_ = led_radius_m;
  model.texture_gray_ = toGray(texture);
  return model;
}

TargetModel TargetModel::loadFromYaml(const std::string& yaml_path, bool load_texture) {
  YAML::Node root;
  try {
    root = YAML::LoadFile(yaml_path);
  } catch (const YAML::BadFile&) {
    throw TargetModelError(yaml_path + ": cannot open the file");
  } catch (const YAML::Exception& e) {
    throw TargetModelError(yaml_path + ": not valid YAML: " + e.what());
  }
  const std::string& src = yaml_path;
  const YAML::Node target = requireNode(root, "target", src, "target");
  const YAML::Node face = requireNode(target, "face", src, "target.face");
  TargetModel model;
  if (target["frame_id"]) model.frame_id_ = target["frame_id"].as<std::string>();
  model.face_width_m_ = requireDouble(face, "width_m", src, "target.face.width_m");
  model.face_height_m_ = requireDouble(face, "height_m", src, "target.face.height_m");
  model.marker_radius_m_ = requireDouble(target, "marker_radius_m", src, "target.marker_radius_m");
  model.led_radius_m_ = requireDouble(target, "led_radius_m", src, "target.led_radius_m");

  const YAML::Node markers = requireNode(target, "markers_m", src, "target.markers_m");
  if (!markers.IsSequence() || markers.size() != static_cast<size_t>(kMarkerCount)) {
    fail(src, "target.markers_m", "must be a list of exactly 5 [x, y, z] points");
  }
  for (int i = 0; i < kMarkerCount; ++i) {
    const std::string field = "target.markers_m[" + std::to_string(i) + "]";
    const YAML::Node m = markers[static_cast<size_t>(i)];
    if (!m.IsSequence() || m.size() != 3) fail(src, field, "must be [x, y, z]");
    try {
      model.markers_m_[static_cast<size_t>(i)] = {m[0].as<double>(), m[1].as<double>(), m[2].as<double>()};
    } catch (const YAML::Exception&) {
      fail(src, field, "not three numbers");
    }
  }
  validate(src, model.face_width_m_, model.face_height_m_, model.markers_m_, model.marker_radius_m_,
           model.led_radius_m_);
  if (target["inner_pattern"]) {
    model.inner_pattern_ = readInnerPattern(target["inner_pattern"], src, model.face_width_m_, model.face_height_m_);
    model.has_inner_pattern_ = true;
  }

  if (load_texture) {
    const YAML::Node texture = requireNode(face, "texture", src, "target.face.texture");
    const std::string name = texture.as<std::string>();
    std::string path = name;
    if (!name.empty() && name.front() != '/') {
      const size_t slash = yaml_path.find_last_of('/');
      path = (slash == std::string::npos ? std::string(".") : yaml_path.substr(0, slash)) + "/" + name;
    }
    const cv::Mat image = cv::imread(path, cv::IMREAD_GRAYSCALE);
    if (image.empty()) fail(src, "target.face.texture", "cannot read image '" + path + "'");
    if (image.cols < 32 || image.rows < 32) fail(src, "target.face.texture", "image smaller than 32x32 px");
    model.texture_gray_ = image;
  }
  return model;
}

Eigen::Matrix3d TargetModel::textureToFace() const {
  // Texture column u runs along +y, row v along -z; the texture's outer edges (u = -0.5, u = W - 0.5)
  // are the face edges.
  const double cols = texture_gray_.empty() ? 1.0 : texture_gray_.cols;
  const double rows = texture_gray_.empty() ? 1.0 : texture_gray_.rows;
  const double sy = face_width_m_ / cols;
  const double sz = face_height_m_ / rows;
  Eigen::Matrix3d map;
  map << sy, 0.0, 0.5 * sy - 0.5 * face_width_m_,  //
      0.0, -sz, 0.5 * face_height_m_ - 0.5 * sz,    //
      0.0, 0.0, 1.0;
  return map;
}

Eigen::Vector3d TargetModel::texturePixelToPoint(const cv::Point2f& pixel) const {
  const Eigen::Vector3d yz = textureToFace() * Eigen::Vector3d(pixel.x, pixel.y, 1.0);
  return {0.0, yz.x(), yz.y()};
}

cv::Point2d TargetModel::pointToTexturePixel(const Eigen::Vector3d& point) const {
  const Eigen::Vector3d uv = textureToFace().inverse() * Eigen::Vector3d(point.y(), point.z(), 1.0);
  return {uv.x(), uv.y()};
}

std::vector<Eigen::Vector3d> TargetModel::faceCorners() const {
  const double hw = 0.5 * face_width_m_;
  const double hh = 0.5 * face_height_m_;
  return {{0.0, -hw, hh}, {0.0, hw, hh}, {0.0, hw, -hh}, {0.0, -hw, -hh}};
}

}  // namespace mono
}  // namespace docking_perception
