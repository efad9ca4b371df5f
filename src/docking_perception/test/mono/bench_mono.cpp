// bench_mono: time of detection + pose on 640x480 frames, single-threaded (cv::setNumThreads(1)).
//
//   bench_mono OUTPUT.json [TARGET_YAML] [--stages NAME,NAME,...]
//
// Stages: mono_full (visible, PnP, every frame a cold start: no track, no hint, the search without a prior),
// mono_tracking (the same with the
// region predicted from the last pose, the face refined at its predicted place first: deployed),
// mono_tracking_near (the same on a second approach, 0.6 m to 0.2 m: the final approach, where the face fills
// more of the image),
// mono_tracking_features (tracking by the feature search in the predicted region only, as before issue 15's
// predict_face_when_tracking), mono_full_paper_5point (the paper's solver, full frame) and
// mono_ir (LED pattern + 5-point solver). The frames are synthetic views of the target (the texture of
// TARGET_YAML when given and readable, with its inner tag drawn, else a seeded synthetic texture), approaching
// from 1.4 m to 0.6 m (mono_tracking_near: 0.6 m to 0.2 m) while yawing. ms_median is the CPU time of the
// estimator's thread (the machine is shared, so wall time measures the neighbours too; it is printed beside).
// Accuracy on the same frames is printed too. --stages runs only the named stages
// (scripts/bench_instructions.py counts each stage's instructions under callgrind, one stage per run).
// Nothing here is a test: it prints figures.
#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <opencv2/core.hpp>
#include <set>
#include <sstream>
#include <string>
#include <vector>

#include "docking_perception/mono/mono_pose_estimator.h"
#include "synthetic_scene.h"

using namespace docking_perception::mono;  // NOLINT: a program, one namespace

namespace {

struct Frame {
  cv::Mat image;
  double stamp_s;
  Eigen::Matrix3d rotation;
  Eigen::Vector3d translation;
};

/// A straight approach along the optical axis: range from_m to to_m in 90 frames at 30 Hz, a lateral drift of
/// amplitude lateral_m, a fixed height offset, the face yawing +-0.4 rad.
struct Approach {
  double from_m;
  double to_m;
  double lateral_m;
  double height_m;
};

std::vector<Frame> visibleApproach(const TargetModel& model, const CameraIntrinsics& camera, const Approach& approach,
                                   int noise_seed) {
  std::vector<Frame> frames;
  for (int i = 0; i < 90; ++i) {
    Frame frame;
    frame.stamp_s = i / 30.0;
    const double s = i / 89.0;
    frame.translation = Eigen::Vector3d(approach.lateral_m * std::sin(2.0 * s), approach.height_m,
                                        approach.from_m - (approach.from_m - approach.to_m) * s);
    frame.rotation = synthetic::facingRotation(0.4 * std::sin(3.0 * s), 0.05, 0.02);
    frame.image = synthetic::renderVisible(model, camera, frame.rotation, frame.translation, noise_seed + i, 2.0,
                                           /*with_inner_pattern=*/true);
    frames.push_back(frame);
  }
  return frames;
}

struct StageFigures {
  std::string name;
  double cpu_ms_median = 0.0;
  double wall_ms_median = 0.0;
  double detection_rate = 0.0;
  double position_error_median_m = 0.0;
  double angle_error_median_deg = 0.0;
  double tracked_fraction = 0.0;
  double predicted_fraction = 0.0;  // of the frames: the pose from the face refined at its predicted place
};

double median(std::vector<double> values) {
  if (values.empty()) return 0.0;
  std::sort(values.begin(), values.end());
  return values[values.size() / 2];
}

StageFigures runStage(const std::string& name, const TargetModel& model, const CameraIntrinsics& camera,
                      const MonoPoseParams& params, const std::vector<Frame>& frames, bool skip_first) {
  MonoPoseEstimator estimator(model, camera, params);
  std::vector<double> cpu;
  std::vector<double> wall;
  std::vector<double> position_errors;
  std::vector<double> angle_errors;
  int valid = 0;
  int tracked = 0;
  int predicted = 0;
  for (size_t i = 0; i < frames.size(); ++i) {
    if (!params.use_tracking_region) estimator.reset();  // the full-frame stages: every frame a cold start
    const auto start = std::chrono::steady_clock::now();
    const MonoPoseResult result = estimator.process(frames[i].image, frames[i].stamp_s);
    const double wall_ms = std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start).count();
    if (skip_first && i == 0) continue;  // the first tracking frame is a full search by necessity
    cpu.push_back(result.processing_time_ms);
    wall.push_back(wall_ms);
    if (result.valid) {
      ++valid;
      tracked += result.used_tracking_region ? 1 : 0;
      predicted += result.used_predicted_face ? 1 : 0;
      position_errors.push_back((result.pose.translation - frames[i].translation).norm());
      angle_errors.push_back(rotationAngleBetween(result.pose.rotation, frames[i].rotation) * 180.0 / M_PI);
    }
  }
  StageFigures figures;
  figures.name = name;
  figures.cpu_ms_median = median(cpu);
  figures.wall_ms_median = median(wall);
  figures.detection_rate = cpu.empty() ? 0.0 : static_cast<double>(valid) / cpu.size();
  figures.tracked_fraction = cpu.empty() ? 0.0 : static_cast<double>(tracked) / cpu.size();
  figures.predicted_fraction = cpu.empty() ? 0.0 : static_cast<double>(predicted) / cpu.size();
  figures.position_error_median_m = median(position_errors);
  figures.angle_error_median_deg = median(angle_errors);
  return figures;
}

}  // namespace

int main(int argc, char** argv) {
  std::vector<std::string> positional;
  std::set<std::string> only_stages;  // empty: every stage
  for (int i = 1; i < argc; ++i) {
    const std::string arg = argv[i];
    if (arg == "--stages" && i + 1 < argc) {
      std::stringstream list(argv[++i]);
      for (std::string name; std::getline(list, name, ',');) only_stages.insert(name);
    } else {
      positional.push_back(arg);
    }
  }
  if (positional.empty() || positional.size() > 2) {
    std::fprintf(stderr, "usage: %s OUTPUT.json [TARGET_YAML] [--stages NAME,NAME,...]\n", argv[0]);
    return 2;
  }
  cv::setNumThreads(1);
  const std::string output = positional[0];

  TargetModel model = synthetic::makeModel(1);
  std::string texture_source = "synthetic texture (seed 1)";
  if (positional.size() > 1) {
    try {
      model = TargetModel::loadFromYaml(positional[1]);
      texture_source = positional[1];
    } catch (const TargetModelError& e) {
      std::fprintf(stderr, "bench_mono: %s; using the synthetic texture\n", e.what());
    }
  }
  const CameraIntrinsics camera = synthetic::defaultCamera();

  // 90 frames at 30 Hz: approach from 1.4 m to 0.6 m, yaw swinging +-0.4 rad, some lateral drift.
  const std::vector<Frame> visible = visibleApproach(model, camera, Approach{1.4, 0.6, 0.05, -0.02}, 1000);
  std::vector<Frame> infrared;
  for (std::size_t i = 0; i < visible.size(); ++i) {
    Frame frame = visible[i];
    std::vector<Eigen::Vector3d> leds;
    for (const auto& m : model.markers()) leds.push_back(frame.rotation * m + frame.translation);
    frame.image = synthetic::renderLedSpots(camera, leds, model.ledRadius(), 2000 + static_cast<int>(i));
    infrared.push_back(frame);
  }

  // 90 frames at 30 Hz near contact, the planner's final approach: 0.6 m to 0.2 m, the same yaw swing, less drift.
  // In the closed loop the visible pose costs most here (the face fills more of the image). The inner tag is drawn on the face (both approaches), as on the real one.
  const std::vector<Frame> near_contact = visibleApproach(model, camera, Approach{0.6, 0.2, 0.02, -0.01}, 3000);

  // The shipped visible configuration: the declared defaults (config/mono_pose_visible.yaml changes none).
  const MonoPoseParams deployed;
  MonoPoseParams full = deployed;
  full.use_tracking_region = false;
  MonoPoseParams tracking = deployed;
  tracking.use_tracking_region = true;
  MonoPoseParams five_point = full;
  five_point.solver = toString(PoseSolverType::kPaperFivePoint);
  MonoPoseParams ir = deployed;
  ir.mode = toString(MonoMode::kIr);
  ir.solver = toString(PoseSolverType::kPaperFivePoint);
  ir.leds.threshold = 140;  // renderLedSpots' spots peak lower than the simulator's saturated LEDs (200 shipped)

  MonoPoseParams tracking_features = tracking;  // predict_face_when_tracking off: the feature search every frame
  tracking_features.predict_face_when_tracking = false;
  struct StagePlan {
    const char* name;
    const MonoPoseParams* params;
    const std::vector<Frame>* frames;
    bool skip_first;
  };
  const std::vector<StagePlan> plans = {{"mono_full", &full, &visible, false},
                                        {"mono_tracking", &tracking, &visible, true},
                                        {"mono_tracking_near", &tracking, &near_contact, true},
                                        {"mono_tracking_features", &tracking_features, &visible, true},
                                        {"mono_full_paper_5point", &five_point, &visible, false},
                                        {"mono_ir", &ir, &infrared, false}};
  std::vector<StageFigures> stages;
  for (const StagePlan& plan : plans) {
    if (!only_stages.empty() && only_stages.count(plan.name) == 0) continue;
    stages.push_back(runStage(plan.name, model, camera, *plan.params, *plan.frames, plan.skip_first));
  }
  if (stages.empty()) {
    std::fprintf(stderr, "bench_mono: --stages names no stage of this program\n");
    return 2;
  }

  std::printf("bench_mono: 640x480, 1 thread, %zu frames, %s\n", visible.size(), texture_source.c_str());
  std::printf("%-24s %9s %8s %9s %9s %9s %9s %8s %9s\n", "stage", "cpu ms", "Hz", "wall ms", "detect", "pos mm",
              "ang deg", "tracked", "predicted");
  for (const StageFigures& s : stages) {
    std::printf("%-24s %9.2f %8.1f %9.2f %9.3f %9.2f %9.3f %8.2f %9.2f\n", s.name.c_str(), s.cpu_ms_median,
                s.cpu_ms_median > 0.0 ? 1000.0 / s.cpu_ms_median : 0.0, s.wall_ms_median, s.detection_rate,
                1000.0 * s.position_error_median_m, s.angle_error_median_deg, s.tracked_fraction,
                s.predicted_fraction);
  }

  std::ofstream out(output);
  if (!out) {
    std::fprintf(stderr, "bench_mono: cannot write %s\n", output.c_str());
    return 1;
  }
  out << "{\"image\": \"640x480\", \"threads\": 1, \"timing\": \"thread CPU time\", \"stages\": {";
  for (size_t i = 0; i < stages.size(); ++i) {
    const StageFigures& s = stages[i];
    char buffer[512];
    std::snprintf(buffer, sizeof(buffer),
                  "%s\"%s\": {\"ms_median\": %.3f, \"hz\": %.1f, \"wall_ms_median\": %.3f, \"detection_rate\": %.3f, "
                  "\"position_error_median_m\": %.5f, \"orientation_error_median_deg\": %.3f}",
                  i == 0 ? "" : ", ", s.name.c_str(), s.cpu_ms_median,
                  s.cpu_ms_median > 0.0 ? 1000.0 / s.cpu_ms_median : 0.0, s.wall_ms_median, s.detection_rate,
                  s.position_error_median_m, s.angle_error_median_deg);
    out << buffer;
  }
  out << "}}\n";
  return 0;
}
