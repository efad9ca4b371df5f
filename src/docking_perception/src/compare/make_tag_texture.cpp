// make_tag_texture: writes the face texture of a tagged target variant from libapriltag's own tag36h11
// codes (apriltag_to_image), at the face size and tag placement the yaml gives (`target.face`,
// `target.apriltag`). Nothing is downloaded.
//
//   make_tag_texture TARGET.yaml OUT.png [--px-per-m 2000] [--background FACE.png]
//
// Without --background: the tag on white paper covering the face (config/target_tagged.yaml). With it:
// the tag, its white ring included, printed over that picture of the face (scaled to the face at
// px-per-m), the rest of the picture kept (config/target_tagged_inset.yaml: our textured face with a
// tag inset, so that AprilTag and our feature-based pose run on the same frames in make bench).
#include <yaml-cpp/yaml.h>

#include <cmath>
#include <iostream>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>
#include <string>

#include "tag_pose.h"

namespace cmp = docking_perception::compare;

namespace {

// The tag's print (black square and white ring) in texture pixels: u along +y, v along -z.
cv::Rect tagPrintRect(const cmp::TagSpec& spec, double face_width_m, double face_height_m, double px_per_m) {
  const int cells = cmp::tagCells(spec).cols;  // the white ring included
  const double print_m = spec.size_m * cells / (cells - 2);
  const double cu = (spec.center_m.y() + face_width_m / 2.0) * px_per_m;
  const double cv_ = (face_height_m / 2.0 - spec.center_m.z()) * px_per_m;
  const double half = 0.5 * print_m * px_per_m;
  const int u0 = static_cast<int>(std::lround(cu - half)), v0 = static_cast<int>(std::lround(cv_ - half));
  const int u1 = static_cast<int>(std::lround(cu + half)), v1 = static_cast<int>(std::lround(cv_ + half));
  return cv::Rect(u0, v0, u1 - u0, v1 - v0);
}

cv::Mat insetTag(const cmp::TagSpec& spec, double w, double h, double px_per_m, const std::string& background_path) {
  const cv::Mat background = cv::imread(background_path, cv::IMREAD_COLOR);
  if (background.empty()) throw std::runtime_error("cannot read " + background_path);
  const cv::Mat tag_only = cmp::makeTagTexture(spec, w, h, px_per_m);
  cv::Mat texture;
  cv::resize(background, texture, tag_only.size(), 0.0, 0.0, cv::INTER_AREA);
  const cv::Rect print = tagPrintRect(spec, w, h, px_per_m);
  if ((print & cv::Rect(0, 0, texture.cols, texture.rows)) != print)
    throw std::runtime_error("the tag's print (white ring included) does not fit on the face");
  cv::Mat print_bgr;
  cv::cvtColor(tag_only(print), print_bgr, cv::COLOR_GRAY2BGR);
  print_bgr.copyTo(texture(print));
  return texture;
}

}  // namespace

int main(int argc, char** argv) {
  if (argc < 3 || argc % 2 == 0) {
    std::cerr << "usage: make_tag_texture TARGET.yaml OUT.png [--px-per-m 2000] [--background FACE.png]\n";
    return 2;
  }
  double px_per_m = 2000.0;
  std::string background_path;
  for (int i = 3; i + 1 < argc; i += 2) {
    const std::string arg = argv[i];
    if (arg == "--px-per-m") {
      px_per_m = std::stod(argv[i + 1]);
    } else if (arg == "--background") {
      background_path = argv[i + 1];
    } else {
      std::cerr << "make_tag_texture: unknown option " << arg << "\n";
      return 2;
    }
  }
  try {
    const auto spec = cmp::loadTagSpec(argv[1]);
    const YAML::Node face = YAML::LoadFile(argv[1])["target"]["face"];
    const double w = face["width_m"].as<double>(), h = face["height_m"].as<double>();
    const cv::Mat texture = background_path.empty() ? cmp::makeTagTexture(spec, w, h, px_per_m)
                                                    : insetTag(spec, w, h, px_per_m, background_path);
    if (!cv::imwrite(argv[2], texture)) {
      std::cerr << "cannot write " << argv[2] << "\n";
      return 1;
    }
    std::cout << "wrote " << argv[2] << " (" << texture.cols << "x" << texture.rows << ", tag36h11 id " << spec.id
              << ", " << spec.size_m << " m" << (background_path.empty() ? "" : ", inset in " + background_path)
              << ")\n";
  } catch (const std::exception& e) {
    std::cerr << "make_tag_texture: " << e.what() << "\n";
    return 1;
  }
  return 0;
}
