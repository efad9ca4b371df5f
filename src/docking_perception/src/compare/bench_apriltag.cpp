// bench_apriltag: AprilTag 3 detection (tag36h11, one thread) + estimate_tag_pose on one fixed 640x480
// frame of the tagged target, repeated; prints and writes the median (make bench, stage `apriltag`).
// With --mono-params, our monocular pose (MonoPoseEstimator, PnP) runs on the same frame too, with the
// tagged target's own texture as its model: the peer comparison on identical pixels (issue 15), stages
// `mono_full_same_frame` (each time a cold start: no track, the search without a prior) and `mono_tracking_same_frame` (the region
// predicted from the last pose).
//
//   bench_apriltag OUT.json [--sequence DIR --target config/target_tagged.yaml]
//                  [--mono-params config/mono_pose_visible.yaml] [--stages NAME,...] [--frames N]
//                  [--decimate F]
//
// With --sequence: frame 0 of a `sim_render --sequence` folder (rendered, rectified) and its intrinsics.
// Without: a synthetic view of the tag texture, port 1 m ahead, f = 550 px (the default tag of
// target_tagged.yaml: 0.192 m, centred on the 0.30 x 0.24 m face). --stages runs only the named stages
// (scripts/bench_instructions.py counts each one's instructions under callgrind, one stage per run).
// Times are CPU time of the thread, medians; exits 1 if a stage misses the target in any frame.
#include <opencv2/core/utility.hpp>
#include <opencv2/imgcodecs.hpp>

#include <algorithm>
#include <cstdio>
#include <fstream>
#include <iostream>
#include <set>
#include <sstream>
#include <string>
#include <vector>

#include "docking_perception/mono/mono_pose_estimator.h"
#include "error_stats.h"
#include "docking_settings/yaml_loader.h"
#include "sequence_io.h"
#include "synthetic_tag_view.h"
#include "tag_pose.h"

namespace cmp = docking_perception::compare;
namespace mono = docking_perception::mono;

namespace {

const char* const kUsage =
    "usage: bench_apriltag OUT.json [--sequence DIR --target TAGGED.yaml] [--mono-params MONO.yaml] "
    "[--stages NAME,...] [--frames N] [--decimate F]\n";
const char* const kAprilTagStage = "apriltag";
const char* const kMonoFullStage = "mono_full_same_frame";
const char* const kMonoTrackingStage = "mono_tracking_same_frame";

struct Options {
  std::string out_path, seq_dir, target_yaml, mono_yaml;
  std::set<std::string> stages;  // empty: every stage the inputs allow
  int frames = 200;
  double decimate = 2.0;
};

// The frame every stage runs on, its intrinsics and (with a sequence) the target's true position.
struct BenchFrame {
  cv::Mat image;
  mono::CameraIntrinsics camera;
  std::string source;
  bool has_truth = false;
  Eigen::Vector3d position_m = Eigen::Vector3d::Zero();
};

struct StageFigures {
  std::string name;
  double ms_median = 0.0;
  double ms_p95 = 0.0;
  int found = 0;
  int frames = 0;
  double position_error_median_m = -1.0;  // kNoTruth when the frame has no truth
  std::string last_failure;                // why the last missed frame was missed
};
constexpr double kNoTruth = -1.0;

bool parseOptions(int argc, char** argv, Options* options) {
  if (argc < 2) return false;
  options->out_path = argv[1];
  for (int i = 2; i + 1 < argc; i += 2) {
    const std::string arg = argv[i], value = argv[i + 1];
    if (arg == "--sequence") options->seq_dir = value;
    else if (arg == "--target") options->target_yaml = value;
    else if (arg == "--mono-params") options->mono_yaml = value;
    else if (arg == "--frames") options->frames = std::max(1, std::stoi(value));
    else if (arg == "--decimate") options->decimate = std::stod(value);
    else if (arg == "--stages") {
      std::stringstream list(value);
      for (std::string name; std::getline(list, name, ',');) options->stages.insert(name);
    } else {
      std::cerr << "unknown option " << arg << "\n";
      return false;
    }
  }
  return true;
}

bool wanted(const Options& options, const std::string& stage) {
  return options.stages.empty() || options.stages.count(stage) > 0;
}

BenchFrame loadFrame(const Options& options, const cmp::TagSpec& spec) {
  BenchFrame frame;
  if (!options.seq_dir.empty()) {
    const cmp::Sequence seq = cmp::readSequence(options.seq_dir);
    frame.camera = seq.camera;
    frame.image = cv::imread(seq.frames.front().image_path, cv::IMREAD_GRAYSCALE);
    if (frame.image.empty()) throw cmp::SequenceError("cannot read " + seq.frames.front().image_path);
    frame.source = seq.frames.front().image_path;
    frame.has_truth = true;
    frame.position_m = seq.frames.front().position_m;
    return frame;
  }
  frame.camera.fx = frame.camera.fy = 550.0;
  frame.camera.cx = 319.5;
  frame.camera.cy = 239.5;
  frame.camera.width = 640;
  frame.camera.height = 480;
  const cv::Mat texture = cmp::makeTagTexture(spec, 0.30, 0.24, 2000.0);
  Eigen::Isometry3d camera_T_target = Eigen::Isometry3d::Identity();
  // Face towards the camera: x_target = -z_camera, y_target = x_camera, z_target = -y_camera.
  camera_T_target.linear() << 0, 1, 0, 0, 0, -1, -1, 0, 0;
  camera_T_target.translation() = Eigen::Vector3d(0.0, 0.0, 1.0);
  frame.image = cmp::renderFaceView(texture, 0.30, 0.24, frame.camera, camera_T_target);
  frame.source = "synthetic view, 1 m";
  frame.has_truth = true;
  frame.position_m = camera_T_target.translation();
  return frame;
}

StageFigures summarise(const std::string& name, const std::vector<double>& ms, int found,
                       const std::vector<double>& position_errors) {
  StageFigures figures;
  figures.name = name;
  figures.ms_median = cmp::percentile(ms, 0.5);
  figures.ms_p95 = cmp::percentile(ms, 0.95);
  figures.found = found;
  figures.frames = static_cast<int>(ms.size());
  if (!position_errors.empty()) figures.position_error_median_m = cmp::percentile(position_errors, 0.5);
  return figures;
}

StageFigures benchAprilTag(const Options& options, const cmp::TagSpec& spec, const BenchFrame& frame) {
  cmp::TagDetector detector(spec, 1, options.decimate);
  detector.detect(frame.image, frame.camera);  // warm-up
  std::vector<double> ms, position_errors;
  std::string failure;
  int found = 0;
  for (int k = 0; k < options.frames; ++k) {
    const cmp::TagResult r = detector.detect(frame.image, frame.camera);
    ms.push_back(r.processing_time_ms);
    if (!r.found) {
      failure = r.status;
      continue;
    }
    ++found;
    if (frame.has_truth) position_errors.push_back((r.camera_T_target.translation() - frame.position_m).norm());
  }
  StageFigures figures = summarise(kAprilTagStage, ms, found, position_errors);
  figures.last_failure = failure;
  return figures;
}

// The same frame at 30 Hz stamps: a still target, so tracking predicts it where it was.
StageFigures benchMono(const std::string& name, const mono::TargetModel& model, const BenchFrame& frame,
                       mono::MonoPoseParams params, bool tracking, int frames) {
  params.use_tracking_region = tracking;
  mono::MonoPoseEstimator estimator(model, frame.camera, params);
  estimator.process(frame.image, 0.0);  // warm-up (and the first pose tracking starts from)
  std::vector<double> ms, position_errors;
  std::string failure;
  int found = 0;
  for (int k = 1; k <= frames; ++k) {
    if (!tracking) estimator.reset();
    const mono::MonoPoseResult r = estimator.process(frame.image, k / 30.0);
    ms.push_back(r.processing_time_ms);
    if (!r.valid) {
      failure = r.status;
      continue;
    }
    ++found;
    if (frame.has_truth) position_errors.push_back((r.pose.translation - frame.position_m).norm());
  }
  StageFigures figures = summarise(name, ms, found, position_errors);
  figures.last_failure = failure;
  return figures;
}

void print(const StageFigures& s) {
  std::printf("  %-26s %7.2f ms CPU median (p95 %.2f), %7.1f Hz; found in %d of %d", s.name.c_str(), s.ms_median,
              s.ms_p95, 1000.0 / s.ms_median, s.found, s.frames);
  if (s.position_error_median_m != kNoTruth) std::printf(", position error %.1f mm", 1000.0 * s.position_error_median_m);
  if (!s.last_failure.empty()) std::printf("; missed: %s", s.last_failure.c_str());
  std::printf("\n");
}

bool writeJson(const std::string& path, const std::vector<StageFigures>& stages) {
  std::ofstream out(path);
  out << "{\"stages\": {";
  for (std::size_t i = 0; i < stages.size(); ++i) {
    const StageFigures& s = stages[i];
    out << (i ? ", " : "") << "\"" << s.name << "\": {\"ms_median\": " << s.ms_median << ", \"hz\": "
        << 1000.0 / s.ms_median << ", \"detection_rate\": " << static_cast<double>(s.found) / s.frames;
    if (s.position_error_median_m != kNoTruth) out << ", \"position_error_median_m\": " << s.position_error_median_m;
    out << "}";
  }
  out << "}}\n";
  return static_cast<bool>(out);
}

}  // namespace

int main(int argc, char** argv) {
  Options options;
  if (!parseOptions(argc, argv, &options)) {
    std::cerr << kUsage;
    return 2;
  }
  cv::setNumThreads(1);
  try {
    cmp::TagSpec spec;
    spec.size_m = 0.192;
    if (!options.target_yaml.empty()) spec = cmp::loadTagSpec(options.target_yaml);
    const BenchFrame frame = loadFrame(options, spec);
    std::vector<StageFigures> stages;
    if (wanted(options, kAprilTagStage)) stages.push_back(benchAprilTag(options, spec, frame));
    if (!options.mono_yaml.empty() && (wanted(options, kMonoFullStage) || wanted(options, kMonoTrackingStage))) {
      if (options.target_yaml.empty()) throw std::invalid_argument("--mono-params needs --target (the model)");
      const mono::MonoPoseParams params = docking_settings::shippedSettings<mono::MonoPoseNodeSettings>(options.mono_yaml).core;
      const mono::TargetModel model = mono::TargetModel::loadFromYaml(options.target_yaml);
      if (wanted(options, kMonoFullStage))
        stages.push_back(benchMono(kMonoFullStage, model, frame, params, false, options.frames));
      if (wanted(options, kMonoTrackingStage))
        stages.push_back(benchMono(kMonoTrackingStage, model, frame, params, true, options.frames));
    }
    if (stages.empty()) throw std::invalid_argument("--stages names no stage these inputs allow");
    std::printf("bench_apriltag: AprilTag 3 (tag36h11, quad_decimate %.1f, 1 thread, detection + estimate_tag_pose)"
                "%s on %s, %dx%d, %d frames:\n",
                options.decimate, options.mono_yaml.empty() ? "" : " and our mono pose", frame.source.c_str(),
                frame.image.cols, frame.image.rows, options.frames);
    for (const StageFigures& s : stages) print(s);
    if (stages.size() > 1 && stages.front().name == kAprilTagStage) {
      for (std::size_t i = 1; i < stages.size(); ++i)
        std::printf("  %s is %.2fx AprilTag's speed on this frame\n", stages[i].name.c_str(),
                    stages.front().ms_median / stages[i].ms_median);
    }
    if (!writeJson(options.out_path, stages)) {
      std::cerr << "cannot write " << options.out_path << "\n";
      return 1;
    }
    for (const StageFigures& s : stages)
      if (s.found != s.frames) return 1;
    return 0;
  } catch (const std::exception& e) {
    std::cerr << "bench_apriltag: " << e.what() << "\n";
    return 1;
  }
}
