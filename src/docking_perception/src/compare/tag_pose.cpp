#include "tag_pose.h"

#include <yaml-cpp/yaml.h>

#include <cmath>
#include <opencv2/imgproc.hpp>

namespace docking_perception {
namespace compare {
namespace {

[[noreturn]] void fail(const std::string& file, const std::string& field, const std::string& what) {
  throw TagError(file + ": " + field + ": " + what);
}

}  // namespace

TagSpec loadTagSpec(const std::string& target_yaml) {
  YAML::Node root;
  try {
    root = YAML::LoadFile(target_yaml);
  } catch (const YAML::Exception& e) {
    throw TagError(target_yaml + ": cannot read: " + e.what());
  }
  const YAML::Node tag = root["target"]["apriltag"];
  if (!tag || !tag.IsMap()) fail(target_yaml, "target.apriltag", "missing (not a tagged target?)");
  TagSpec spec;
  try {
    spec.family = tag["family"] ? tag["family"].as<std::string>() : spec.family;
    if (!tag["id"]) fail(target_yaml, "target.apriltag.id", "missing");
    spec.id = tag["id"].as<int>();
    if (!tag["size_m"]) fail(target_yaml, "target.apriltag.size_m", "missing");
    spec.size_m = tag["size_m"].as<double>();
    const YAML::Node c = tag["center_m"];
    if (c) {
      if (!c.IsSequence() || c.size() != 3) fail(target_yaml, "target.apriltag.center_m", "must be [x, y, z]");
      for (std::size_t i = 0; i < 3; ++i) spec.center_m(static_cast<int>(i)) = c[i].as<double>();
    }
  } catch (const YAML::Exception& e) {
    throw TagError(target_yaml + ": target.apriltag: " + e.what());
  }
  if (spec.family != "tag36h11") fail(target_yaml, "target.apriltag.family", "only tag36h11 is supported");
  if (spec.id < 0 || spec.id >= 587) fail(target_yaml, "target.apriltag.id", "must be in [0, 586] for tag36h11");
  if (!(spec.size_m > 0.0) || !std::isfinite(spec.size_m)) fail(target_yaml, "target.apriltag.size_m", "must be > 0");
  if (std::abs(spec.center_m.x()) > 1e-9) fail(target_yaml, "target.apriltag.center_m", "must lie on the face, x = 0");
  return spec;
}

cv::Mat makeTagTexture(const TagSpec& spec, double face_width_m, double face_height_m, double px_per_m, int black,
                       int paper) {
  const cv::Mat tag = tagCells(spec);  // total_width cells: the white ring included
  const int cells_black = tag.cols - 2;  // tag36h11: the black square is the print less its white ring
  const double cell_m = spec.size_m / cells_black;
  const int W = static_cast<int>(std::lround(face_width_m * px_per_m));
  const int H = static_cast<int>(std::lround(face_height_m * px_per_m));
  cv::Mat texture(H, W, CV_8UC1, cv::Scalar(paper));
  // Tag centre in texture pixels (u along +y, v along -z, pixel edges at integer coordinates here).
  const double cu = (spec.center_m.y() + face_width_m / 2.0) * px_per_m;
  const double cv_ = (face_height_m / 2.0 - spec.center_m.z()) * px_per_m;
  const int n = tag.cols;
  const double half = 0.5 * n * cell_m * px_per_m;
  for (int r = 0; r < n; ++r) {
    for (int c = 0; c < n; ++c) {
      const uint8_t value = tag.at<uchar>(r, c);
      const int u0 = static_cast<int>(std::lround(cu - half + c * cell_m * px_per_m));
      const int u1 = static_cast<int>(std::lround(cu - half + (c + 1) * cell_m * px_per_m));
      const int v0 = static_cast<int>(std::lround(cv_ - half + r * cell_m * px_per_m));
      const int v1 = static_cast<int>(std::lround(cv_ - half + (r + 1) * cell_m * px_per_m));
      const cv::Rect cell = cv::Rect(u0, v0, u1 - u0, v1 - v0) & cv::Rect(0, 0, W, H);
      if (cell.area() > 0) texture(cell).setTo(value < 128 ? black : paper);
    }
  }
  return texture;
}

}  // namespace compare
}  // namespace docking_perception
