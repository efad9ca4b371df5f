// make_target_print: a printable target face from any image, with the five reference dots on white
// rings at the positions target.yaml gives (docking_perception README, "Your own target").
//
//   make_target_print IMAGE --target config/target.yaml --out print.png [--width-px N]
//
// The image is cropped (centred) to the face's aspect and scaled to N px wide (default 1800: 152 dpi
// on a 0.30 m face). Print it at exactly the face size of target.yaml, then point target.face.texture
// at the PNG and run check_target_print first. Exit status: 0 written, 2 bad arguments or files.
#include <cstdlib>
#include <iostream>
#include <string>

#include <opencv2/imgcodecs.hpp>

#include "docking_perception/target_print/target_print.h"

int main(int argc, char** argv) {
  using namespace docking_perception;
  std::string image_path, target_path, out_path;
  target_print::ComposeOptions options;
  for (int i = 1; i < argc; ++i) {
    const std::string arg = argv[i];
    const bool has_value = i + 1 < argc;
    if (arg == "--target" && has_value) {
      target_path = argv[++i];
    } else if (arg == "--out" && has_value) {
      out_path = argv[++i];
    } else if (arg == "--width-px" && has_value) {
      options.width_px = std::atoi(argv[++i]);
    } else if (!arg.empty() && arg[0] != '-' && image_path.empty()) {
      image_path = arg;
    } else {
      image_path.clear();
      break;
    }
  }
  if (image_path.empty() || target_path.empty() || out_path.empty()) {
    std::cerr << "usage: make_target_print IMAGE --target TARGET.yaml --out PRINT.png [--width-px N]\n";
    return 2;
  }
  try {
    const mono::TargetModel model = mono::TargetModel::loadFromYaml(target_path, false);
    const cv::Mat image = cv::imread(image_path, cv::IMREAD_COLOR);
    if (image.empty()) {
      std::cerr << "make_target_print: cannot read the image " << image_path << "\n";
      return 2;
    }
    const cv::Mat print = target_print::composePrint(image, model, options);
    if (!cv::imwrite(out_path, print)) {
      std::cerr << "make_target_print: cannot write " << out_path << "\n";
      return 2;
    }
    std::cout << "make_target_print: wrote " << out_path << " (" << print.cols << "x" << print.rows
              << " px); print it at " << model.faceWidth() << " x " << model.faceHeight()
              << " m.\nNext: check_target_print --target " << target_path << " --print " << out_path
              << "\nthen set target.face.texture in " << target_path << " to this file.\n";
    return 0;
  } catch (const std::exception& error) {
    std::cerr << "make_target_print: " << error.what() << "\n";
    return 2;
  }
}
