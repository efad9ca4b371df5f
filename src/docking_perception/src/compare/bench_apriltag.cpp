// bench_apriltag: AprilTag 3 detection (tag36h11, one thread) + estimate_tag_pose on one fixed 640x480
// frame of the tagged target, repeated; prints and writes the median (make bench, stage `apriltag`).
//
//   bench_apriltag OUT.json [--sequence DIR --target config/target_tagged.yaml] [--frames N] [--decimate F]
//
// With --sequence: frame 0 of a `sim_render --sequence` folder (rendered, rectified) and its intrinsics.
// Without: a synthetic view of the tag texture, port 1 m ahead, f = 550 px (the default tag of
// target_tagged.yaml: 0.192 m, centred on the 0.30 x 0.24 m face).
#include <opencv2/core/utility.hpp>
#include <opencv2/imgcodecs.hpp>

#include <algorithm>
#include <cstdio>
#include <fstream>
#include <iostream>
#include <string>
#include <vector>

#include "error_stats.h"
#include "sequence_io.h"
#include "synthetic_tag_view.h"
#include "tag_pose.h"

namespace cmp = docking_perception::compare;

int main(int argc, char** argv) {
  if (argc < 2) {
    std::cerr << "usage: bench_apriltag OUT.json [--sequence DIR --target TAGGED.yaml] [--frames N] [--decimate F]\n";
    return 2;
  }
  const std::string out_path = argv[1];
  std::string seq_dir, target_yaml;
  int frames = 200;
  double decimate = 2.0;
  for (int i = 2; i + 1 < argc; i += 2) {
    const std::string arg = argv[i], value = argv[i + 1];
    if (arg == "--sequence") seq_dir = value;
    else if (arg == "--target") target_yaml = value;
    else if (arg == "--frames") frames = std::max(1, std::stoi(value));
    else if (arg == "--decimate") decimate = std::stod(value);
    else {
      std::cerr << "unknown option " << arg << "\n";
      return 2;
    }
  }
  cv::setNumThreads(1);
  try {
    cmp::TagSpec spec;
    spec.size_m = 0.192;
    if (!target_yaml.empty()) spec = cmp::loadTagSpec(target_yaml);
    cv::Mat image;
    docking_perception::mono::CameraIntrinsics camera;
    std::string source;
    if (!seq_dir.empty()) {
      const cmp::Sequence seq = cmp::readSequence(seq_dir);
      camera = seq.camera;
      image = cv::imread(seq.frames.front().image_path, cv::IMREAD_GRAYSCALE);
      if (image.empty()) throw cmp::SequenceError("cannot read " + seq.frames.front().image_path);
      source = seq.frames.front().image_path;
    } else {
      camera.fx = camera.fy = 550.0;
      camera.cx = 319.5;
      camera.cy = 239.5;
      camera.width = 640;
      camera.height = 480;
      const cv::Mat texture = cmp::makeTagTexture(spec, 0.30, 0.24, 2000.0);
      Eigen::Isometry3d camera_T_target = Eigen::Isometry3d::Identity();
      // Face towards the camera: x_target = -z_camera, y_target = x_camera, z_target = -y_camera.
      camera_T_target.linear() << 0, 1, 0, 0, 0, -1, -1, 0, 0;
      camera_T_target.translation() = Eigen::Vector3d(0.0, 0.0, 1.0);
      image = cmp::renderFaceView(texture, 0.30, 0.24, camera, camera_T_target);
      source = "synthetic view, 1 m";
    }
    cmp::TagDetector detector(spec, 1, decimate);
    detector.detect(image, camera);  // warm-up
    std::vector<double> ms;
    int found = 0;
    for (int k = 0; k < frames; ++k) {
      const cmp::TagResult r = detector.detect(image, camera);
      ms.push_back(r.processing_time_ms);
      found += r.found ? 1 : 0;
    }
    const double median = cmp::percentile(ms, 0.5);
    std::printf("apriltag (tag36h11, quad_decimate %.1f, 1 thread, detection + estimate_tag_pose) on %s, %dx%d:\n"
                "  %.2f ms CPU median over %d runs (p95 %.2f), %.1f Hz; tag found in %d of %d\n",
                decimate, source.c_str(), image.cols, image.rows, median, frames, cmp::percentile(ms, 0.95),
                1000.0 / median, found, frames);
    std::ofstream out(out_path);
    out << "{\"stages\": {\"apriltag\": {\"ms_median\": " << median << ", \"hz\": " << 1000.0 / median << "}}}\n";
    if (!out) {
      std::cerr << "cannot write " << out_path << "\n";
      return 1;
    }
    return found == frames ? 0 : 1;
  } catch (const std::exception& e) {
    std::cerr << "bench_apriltag: " << e.what() << "\n";
    return 1;
  }
}
