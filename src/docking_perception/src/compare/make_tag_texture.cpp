// make_tag_texture: writes the face texture of a tagged target variant (config/target_tagged.yaml)
// from libapriltag's own tag36h11 codes (apriltag_to_image), at the face size and tag placement the
// yaml gives (`target.face`, `target.apriltag`). Nothing is downloaded.
//
//   make_tag_texture config/target_tagged.yaml OUT.png [--px-per-m 2000]
#include <yaml-cpp/yaml.h>

#include <iostream>
#include <opencv2/imgcodecs.hpp>
#include <string>

#include "tag_pose.h"

int main(int argc, char** argv) {
  if (argc != 3 && argc != 5) {
    std::cerr << "usage: make_tag_texture TARGET_TAGGED.yaml OUT.png [--px-per-m 2000]\n";
    return 2;
  }
  double px_per_m = 2000.0;
  if (argc == 5) px_per_m = std::stod(argv[4]);
  try {
    const auto spec = docking_perception::compare::loadTagSpec(argv[1]);
    const YAML::Node face = YAML::LoadFile(argv[1])["target"]["face"];
    const double w = face["width_m"].as<double>(), h = face["height_m"].as<double>();
    const cv::Mat texture = docking_perception::compare::makeTagTexture(spec, w, h, px_per_m);
    if (!cv::imwrite(argv[2], texture)) {
      std::cerr << "cannot write " << argv[2] << "\n";
      return 1;
    }
    std::cout << "wrote " << argv[2] << " (" << texture.cols << "x" << texture.rows << ", tag36h11 id " << spec.id
              << ", " << spec.size_m << " m)\n";
  } catch (const std::exception& e) {
    std::cerr << "make_tag_texture: " << e.what() << "\n";
    return 1;
  }
  return 0;
}
