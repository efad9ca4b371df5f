// check_target_print: does a face print have enough texture and contrast for mono_pose? Run it before
// printing (docking_perception README, "Your own target").
//
//   check_target_print --target config/target.yaml [--print IMAGE] [--mono-params FILE]
//                      [--blur SIGMA_PX] [--noise SIGMA_DN]
//
// --print: check IMAGE as the face (e.g. make_target_print's output) instead of the texture the
// target.yaml names; the face size and markers still come from the target.yaml. --mono-params: the
// visible mono_pose parameters (default: mono_pose_visible.yaml beside the target.yaml).
// Exit status: 0 PASS, 1 FAIL, 2 bad arguments or unreadable files.
#include <cstdlib>
#include <iostream>
#include <string>

#include <opencv2/imgcodecs.hpp>

#include "docking_perception/target_print/target_print.h"
#include "docking_settings/yaml_loader.h"

namespace {

const char* const kUsage =
    "usage: check_target_print --target TARGET.yaml [--print IMAGE] [--mono-params FILE] "
    "[--blur SIGMA_PX] [--noise SIGMA_DN]\n";

std::string folderOf(const std::string& path) {
  const auto slash = path.find_last_of('/');
  return slash == std::string::npos ? "." : path.substr(0, slash);
}

}  // namespace

int main(int argc, char** argv) {
  using namespace docking_perception;
  std::string target_path, print_path, mono_params_path;
  target_print::CheckParams params;
  for (int i = 1; i < argc; ++i) {
    const std::string arg = argv[i];
    const bool has_value = i + 1 < argc;
    if (arg == "--target" && has_value) {
      target_path = argv[++i];
    } else if (arg == "--print" && has_value) {
      print_path = argv[++i];
    } else if (arg == "--mono-params" && has_value) {
      mono_params_path = argv[++i];
    } else if (arg == "--blur" && has_value) {
      params.blur_sigma_px = std::atof(argv[++i]);
    } else if (arg == "--noise" && has_value) {
      params.noise_sigma_dn = std::atof(argv[++i]);
    } else {
      std::cerr << kUsage;
      return 2;
    }
  }
  if (target_path.empty()) {
    std::cerr << kUsage;
    return 2;
  }
  if (mono_params_path.empty()) mono_params_path = folderOf(target_path) + "/mono_pose_visible.yaml";
  try {
    mono::TargetModel model = mono::TargetModel::loadFromYaml(target_path, print_path.empty());
    if (!print_path.empty()) {
      const cv::Mat print = cv::imread(print_path, cv::IMREAD_COLOR);
      if (print.empty()) {
        std::cerr << "check_target_print: cannot read the print " << print_path << "\n";
        return 2;
      }
      model = mono::TargetModel::fromParts(model.faceWidth(), model.faceHeight(), model.markers(),
                                           model.markerRadius(), model.ledRadius(), print);
    }
    const mono::MonoPoseParams mono_params =
        docking_settings::shippedSettings<mono::MonoPoseNodeSettings>(mono_params_path).core;
    const target_print::PrintReport report =
        target_print::checkPrint(model, mono_params.features, params);
    std::cout << "check_target_print: " << (print_path.empty() ? target_path : print_path) << "\n"
              << target_print::formatReport(report, params);
    return report.passed ? 0 : 1;
  } catch (const std::exception& error) {
    std::cerr << "check_target_print: " << error.what() << "\n";
    return 2;
  }
}
