// bench_disparity: single-thread timing of the far-range pipeline on a fixed rendered 640x480 pair.
// A program that prints figures, never a test (timings depend on the machine and its load).
//
//   bench_disparity OUTPUT.json [--frames N] [--config-dir DIR]
//                   [--left RAW.png --right RAW.png] [--debug-image OUT.png]
//                   [--disparity-out OUT.tiff] [--disparity-range N] [--window]
//
// The far stage as perception.launch runs it (config/far_stereo.yaml): each raw frame converted to grey and
// rectified (WindowRectifier), block matching with the matcher of config/stereo_image_proc.yaml, the
// detector. --disparity-range overrides the matcher's range (a multiple of 16). --window: the stage on the
// tracking window alone (config/far_stereo.yaml window_*, the default while the target is tracked; stages
// named window_*), placed around the port that an untimed pass over the whole image finds, as
// far_stereo_rectify places it around the fused estimate.
//
// Without --left/--right the pair is rendered here (test/disparity/synthetic_stereo.h: the target
// face-on at 3 m, its panels, a floor and a wall) and distorted with the calibration, so the
// rectification has real work; with them, raw frames from the simulator (docking_sim's sim_render)
// are used as the simulator publishes them (bgr8): converted to grey (image_proc/debayer) and
// rectified (image_proc/rectify) inside the rectify stage, as perception.launch does.
//
// Stages: rectify (grey conversion of colour frames and cv::remap of both images with the maps of
// config/cameras/stereo_*.yaml),
// disparity (the matcher of config/stereo_image_proc.yaml, converted to float as stereo_image_proc
// does), detection (DisparityDetector with config/disparity_detector.yaml), and disparity_total
// (all three, timed as one). Times are the thread's CPU time (clock_gettime
// CLOCK_THREAD_CPUTIME_ID), medians over the frames; the wall time is printed beside. Writes {"image": "640x480", "threads": 1, "stages": {NAME: {"ms_median",
// "hz"}}} to OUTPUT.json.
#include <algorithm>
#include <chrono>
#include <ctime>
#include <cstdlib>
#include <fstream>
#include <iomanip>
#include <iostream>
#include <map>
#include <string>
#include <vector>

#include <opencv2/calib3d.hpp>
#include <opencv2/core.hpp>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

#include "docking_perception/disparity/disparity_detector.h"
#include "docking_perception/disparity/face_appearance.h"
#include "docking_perception/mono/target_model.h"
#include "docking_msgs/thread_cpu_time.h"
#include "synthetic_stereo.h"

namespace {

using docking_perception::disparity::DisparityDetector;
using docking_perception::disparity::Detection;
using docking_perception::disparity::StereoGeometry;
namespace testing = docking_perception::disparity::testing;

const char* const kUsage =
    "usage: bench_disparity OUTPUT.json [--frames N] [--config-dir DIR] [--left RAW.png --right "
    "RAW.png] [--debug-image OUT.png] [--disparity-out OUT.tiff] [--disparity-range N] "
    "[--window]\n";

double medianOf(std::vector<double> values) {
  std::sort(values.begin(), values.end());
  const std::size_t n = values.size();
  return n % 2 ? values[n / 2] : 0.5 * (values[n / 2 - 1] + values[n / 2]);
}

// The raw (distorted) image a camera with `calibration` would take of the rectified `rectified`:
// for each raw pixel, look up where it lands after rectification.
cv::Mat distort(const cv::Mat& rectified, const testing::CameraCalibration& calibration) {
  std::vector<cv::Point2f> raw_pixels;
  raw_pixels.reserve(static_cast<std::size_t>(calibration.size.area()));
  for (int v = 0; v < calibration.size.height; ++v) {
    for (int u = 0; u < calibration.size.width; ++u) raw_pixels.emplace_back(u, v);
  }
  std::vector<cv::Point2f> rectified_pixels;
  cv::undistortPoints(raw_pixels, rectified_pixels, calibration.camera_matrix,
                      calibration.distortion, calibration.rectification, calibration.projection);
  cv::Mat map(calibration.size, CV_32FC2);
  for (int v = 0; v < calibration.size.height; ++v) {
    for (int u = 0; u < calibration.size.width; ++u) {
      const cv::Point2f& p = rectified_pixels[static_cast<std::size_t>(v * calibration.size.width + u)];
      map.at<cv::Vec2f>(v, u) = cv::Vec2f(p.x, p.y);
    }
  }
  cv::Mat raw;
  cv::remap(rectified, raw, map, cv::noArray(), cv::INTER_LINEAR);
  return raw;
}

// What perception.launch does to each camera of the pair: bgr8 to grey (debayer's image_mono), then the far
// stage's rectification (far_stereo_rectify).
// Not inlined: scripts/bench_instructions.py counts this step's instructions by its name under callgrind.
// `window`: only that part of the rectified images (the tracking window); empty: all of them.
__attribute__((noinline)) void rectifyPair(const cv::Mat& left_raw, const cv::Mat& right_raw,
                                           const docking_perception::disparity::WindowRectifier& left,
                                           const docking_perception::disparity::WindowRectifier& right,
                                           const cv::Rect& window, cv::Mat* left_rect, cv::Mat* right_rect) {
  cv::Mat left_mono = left_raw, right_mono = right_raw;
  if (left_raw.channels() == 3) {
    cv::cvtColor(left_raw, left_mono, cv::COLOR_BGR2GRAY);
    cv::cvtColor(right_raw, right_mono, cv::COLOR_BGR2GRAY);
  }
  const cv::Rect area = window.area() > 0 ? window : cv::Rect(cv::Point(0, 0), left.outputSize());
  left.rectifyWindow(left_mono, area, left_rect);
  right.rectifyWindow(right_mono, area, right_rect);
}

// The tracking window as far_stereo_rectify places it: around the port an (untimed) pass over the whole
// image finds, standing in for the fused estimate. Throws when the target is not found or no window fits.
cv::Rect placeWindow(const cv::Mat& left_raw, const cv::Mat& right_raw,
                     const docking_perception::disparity::WindowRectifier& left,
                     const docking_perception::disparity::WindowRectifier& right, cv::StereoMatcher& matcher,
                     const DisparityDetector& detector, const StereoGeometry& geometry,
                     const testing::MatcherSettings& settings,
                     const docking_perception::disparity::TrackingWindowParams& params) {
  cv::Mat left_rect, right_rect;
  rectifyPair(left_raw, right_raw, left, right, cv::Rect(), &left_rect, &right_rect);
  const cv::Mat disparity = testing::computeDisparity(matcher, left_rect, right_rect);
  const Detection whole = detector.detect(disparity, geometry, settings.min_disparity, testing::maxDisparity(settings),
                                          testing::matcherValidRegion(settings, disparity.size()));
  if (!whole.found) throw std::runtime_error("--window: the whole image does not find the target: " + whole.reason);
  const auto window = docking_perception::disparity::trackingWindow(testing::projectionOf(geometry), whole.position_m,
                                                                    disparity.size(),
                                                                    testing::matcherReachOf(settings), params);
  if (!window) throw std::runtime_error("--window: no tracking window fits the port found");
  return *window;
}

struct Options {
  std::string output_path, left_path, right_path, debug_path, disparity_path;
  std::string config_dir = DISPARITY_CONFIG_DIR;
  int frames = 100;
  int disparity_range_override = 0;  // 0: the configured (scaled) range
  bool use_window = false;
};

/// False on a malformed command line (then kUsage).
bool parseArguments(int argc, char** argv, Options* o) {
  for (int i = 1; i < argc; ++i) {
    const std::string arg = argv[i];
    if (arg == "--frames" && i + 1 < argc) {
      o->frames = std::max(1, std::atoi(argv[++i]));
    } else if (arg == "--config-dir" && i + 1 < argc) {
      o->config_dir = argv[++i];
    } else if (arg == "--left" && i + 1 < argc) {
      o->left_path = argv[++i];
    } else if (arg == "--right" && i + 1 < argc) {
      o->right_path = argv[++i];
    } else if (arg == "--debug-image" && i + 1 < argc) {
      o->debug_path = argv[++i];
    } else if (arg == "--disparity-range" && i + 1 < argc) {
      o->disparity_range_override = std::atoi(argv[++i]);
    } else if (arg == "--window") {
      o->use_window = true;
    } else if (arg == "--disparity-out" && i + 1 < argc) {
      o->disparity_path = argv[++i];  // float disparity of the last frame, px, for offline analysis
    } else if (!arg.empty() && arg[0] != '-' && o->output_path.empty()) {
      o->output_path = arg;
    } else {
      return false;
    }
  }
  return !(o->output_path.empty() || o->left_path.empty() != o->right_path.empty() ||
           o->disparity_range_override % 16 != 0 || o->disparity_range_override < 0);
}

// The fixed scene's truth: the target face-on at 3 m, slightly off-axis.
constexpr double kTruthX = 0.3, kTruthY = 0.0, kTruthZ = 3.0;

/// The configuration (config_dir's calibrations, matcher, far stage and detector settings, target) and
/// the raw pair: the fixed synthetic scene (target, floor, a wall at 8 m) distorted with the
/// calibration, or --left/--right as published.
struct BenchInputs {
  testing::CameraCalibration left_calibration, right_calibration;
  docking_perception::disparity::FarStereoSettings far_stereo;
  testing::MatcherSettings settings;
  docking_perception::disparity::DetectorParams params;
  docking_perception::disparity::TargetShape target_shape;
  docking_perception::disparity::RigGeometry rig;
  testing::SyntheticScene scene;
  cv::Mat left_raw, right_raw;
};

/// Throws on a bad configuration; false (reported) when --left/--right cannot be used.
bool loadInputs(const Options& o, BenchInputs* in) {
  in->left_calibration = testing::loadCameraCalibration(o.config_dir + "/cameras/stereo_left.yaml");
  in->right_calibration = testing::loadCameraCalibration(o.config_dir + "/cameras/stereo_right.yaml");
  in->far_stereo = testing::shippedFarStereoSettings(o.config_dir);
  in->settings = testing::loadMatcherSettings(o.config_dir + "/stereo_image_proc.yaml");
  in->params = testing::shippedDetectorSettings(o.config_dir).detector;
  in->target_shape = docking_perception::disparity::loadTargetShape(o.config_dir + "/target.yaml");
  in->rig = testing::shippedRig(o.config_dir);
  if (o.disparity_range_override > 0) in->settings.disparity_range = o.disparity_range_override;

  in->scene = testing::targetScene(kTruthX, kTruthY, kTruthZ, 8.0);
  in->scene.focal_px = in->left_calibration.projection.at<double>(0, 0);
  in->scene.cx_px = in->left_calibration.projection.at<double>(0, 2);
  in->scene.cy_px = in->left_calibration.projection.at<double>(1, 2);
  in->scene.baseline_m = -in->right_calibration.projection.at<double>(0, 3) /
                         in->right_calibration.projection.at<double>(0, 0);
  cv::Mat left_rectified_truth, right_rectified_truth;
  testing::renderStereoPair(in->scene, &left_rectified_truth, &right_rectified_truth);
  in->left_raw = distort(left_rectified_truth, in->left_calibration);
  in->right_raw = distort(right_rectified_truth, in->right_calibration);
  if (o.left_path.empty()) return true;
  // As published (the simulator's cameras are bgr8): image_proc rectifies all channels.
  in->left_raw = cv::imread(o.left_path, cv::IMREAD_UNCHANGED);
  in->right_raw = cv::imread(o.right_path, cv::IMREAD_UNCHANGED);
  if (in->left_raw.empty() || in->right_raw.empty()) {
    std::cerr << "bench_disparity: cannot read " << (in->left_raw.empty() ? o.left_path : o.right_path) << "\n";
    return false;
  }
  if (in->left_raw.size() != in->left_calibration.size || in->right_raw.size() != in->right_calibration.size) {
    std::cerr << "bench_disparity: frame size differs from the calibration's " << in->left_calibration.size << "\n";
    return false;
  }
  return true;
}

/// The far stage as perception.launch runs it, on the whole image or on the tracking window.
struct FarStage {
  FarStage(const Options& o, const BenchInputs& in)
      : left_rectifier(testing::pinholeOf(in.left_calibration)),
        right_rectifier(testing::pinholeOf(in.right_calibration)),
        matcher(testing::createMatcher(in.settings)),
        detector(in.params, in.target_shape, in.rig),
        // The appearance check the node runs on a found blob (face_appearance.h), part of the detection's cost.
        target_model(docking_perception::mono::TargetModel::loadFromYaml(o.config_dir + "/target.yaml")),
        appearance_check(target_model.textureGray(), target_model.faceWidth(), target_model.faceHeight()),
        geometry(testing::geometryOf(in.scene)) {
    const cv::Size rectified_size = left_rectifier.outputSize();
    if (o.use_window) {
      window = placeWindow(in.left_raw, in.right_raw, left_rectifier, right_rectifier, *matcher, detector, geometry,
                           in.settings, in.far_stereo.window);
    }
    window_geometry = geometry;
    if (o.use_window) {
      image_window.offset = window.tl();
      image_window.full_size = rectified_size;
      window_geometry.cx_px -= window.x;
      window_geometry.cy_px -= window.y;
    }
    valid_region = testing::matcherValidRegion(in.settings, o.use_window ? window.size() : rectified_size);
  }

  const docking_perception::disparity::WindowRectifier left_rectifier, right_rectifier;
  cv::Ptr<cv::StereoMatcher> matcher;
  const DisparityDetector detector;
  const docking_perception::mono::TargetModel target_model;
  const docking_perception::disparity::FaceAppearanceCheck appearance_check;
  const StereoGeometry geometry;
  cv::Rect window;  // empty: the whole image
  docking_perception::disparity::ImageWindow image_window;
  StereoGeometry window_geometry;
  cv::Rect valid_region;
};

/// Per stage, the CPU ms of each timed frame; the last frame's detection and appearance; wall ms per frame.
struct BenchRun {
  std::map<std::string, std::vector<double>> samples;
  Detection detection;
  docking_perception::disparity::AppearanceResult appearance;
  double wall_ms = 0.0;
};

/// Three untimed warm-up frames, then `frames` timed ones: rectify, disparity, detection (with the
/// appearance check when enabled).
BenchRun timeFrames(const Options& o, const BenchInputs& in, FarStage& stage) {
  // CPU time of this thread: on a shared machine, wall time measures the other users too.
  using docking_msgs::threadCpuMs;
  auto ms_since = [](double start_ms) { return threadCpuMs() - start_ms; };
  const auto wall_start = std::chrono::steady_clock::now();
  BenchRun run;
  const int warmup = 3;
  for (int frame = 0; frame < o.frames + warmup; ++frame) {
    const auto start = threadCpuMs();
    cv::Mat left_rect, right_rect;
    rectifyPair(in.left_raw, in.right_raw, stage.left_rectifier, stage.right_rectifier, stage.window, &left_rect,
                &right_rect);
    const double rectify_ms = ms_since(start);
    const auto disparity_start = threadCpuMs();
    const cv::Mat disparity = testing::computeDisparity(*stage.matcher, left_rect, right_rect);
    const double disparity_ms = ms_since(disparity_start);
    const auto detection_start = threadCpuMs();
    run.detection = stage.detector.detect(disparity, stage.window_geometry, in.settings.min_disparity,
                                          testing::maxDisparity(in.settings), stage.valid_region, {},
                                          stage.image_window);
    if (in.params.appearance.check_enabled) {
      run.appearance = docking_perception::disparity::confirmByAppearance(
          stage.appearance_check, left_rect, disparity, stage.window_geometry, in.params.appearance, &run.detection);
    }
    const double detection_ms = ms_since(detection_start);
    const double total_ms = ms_since(start);
    if (frame < warmup) continue;
    run.samples["rectify"].push_back(rectify_ms);
    run.samples["disparity"].push_back(disparity_ms);
    run.samples["detection"].push_back(detection_ms);
    run.samples["disparity_total"].push_back(total_ms);
  }
  run.wall_ms = std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - wall_start).count() /
                (o.frames + warmup);
  return run;
}

/// The header line, the per-stage medians (stdout and OUTPUT.json) and the CPU against wall note.
/// False (reported) when OUTPUT.json cannot be written.
bool reportTimes(const Options& o, const BenchInputs& in, const FarStage& stage, BenchRun& run) {
  const cv::Size rectified_size = stage.left_rectifier.outputSize();
  const cv::Rect& window = stage.window;
  double cpu_total_ms = 0.0;
  for (double ms : run.samples["disparity_total"]) cpu_total_ms += ms;
  std::cout << "bench_disparity: " << (o.left_path.empty() ? "synthetic grey pair" : o.left_path) << ", "
            << rectified_size.width << "x" << rectified_size.height
            << (o.use_window ? " (tracking window " + std::to_string(window.width) + "x" +
                                   std::to_string(window.height) + " at (" + std::to_string(window.x) + ", " +
                                   std::to_string(window.y) + "))"
                             : std::string())
            << ", 1 thread, " << o.frames << " frames, matcher "
            << (in.settings.stereo_algorithm == 0 ? "StereoBM" : "StereoSGBM") << " range "
            << (in.settings.disparity_range / 16) * 16 << " window " << (in.settings.correlation_window_size | 1)
            << "\n";
  std::ofstream json(o.output_path);
  if (!json) {
    std::cerr << "bench_disparity: cannot write " << o.output_path << "\n";
    return false;
  }
  json << std::fixed << std::setprecision(3);
  json << "{\"image\": \"" << rectified_size.width << "x" << rectified_size.height << "\", \"threads\": 1, \"stages\": {";
  bool first = true;
  // The stage on the tracking window is named apart: make bench runs both.
  const std::string prefix = o.use_window ? "window_" : "";
  for (const char* stage_name : {"rectify", "disparity", "detection", "disparity_total"}) {
    const double ms = medianOf(run.samples[stage_name]);
    const double hz = ms > 0.0 ? 1000.0 / ms : 0.0;
    std::cout << "  " << std::left << std::setw(26) << prefix + stage_name << std::right << std::fixed
              << std::setprecision(2) << std::setw(8) << ms << " ms median  " << std::setw(8) << hz << " Hz\n";
    json << (first ? "" : ", ") << "\"" << prefix << stage_name << "\": {\"ms_median\": " << ms << ", \"hz\": " << hz
         << "}";
    first = false;
  }
  json << "}}\n";
  std::cout << std::setprecision(2) << "  (thread CPU time; wall time per frame " << run.wall_ms << " ms against "
            << cpu_total_ms / o.frames << " ms CPU: the difference is other load on the machine)\n";
  return true;
}

/// --debug-image and --disparity-out: one more (untimed) frame's disparity.
void writeDebugOutputs(const Options& o, const BenchInputs& in, FarStage& stage, const Detection& detection) {
  if (o.debug_path.empty() && o.disparity_path.empty()) return;
  cv::Mat left_rect, right_rect;
  rectifyPair(in.left_raw, in.right_raw, stage.left_rectifier, stage.right_rectifier, stage.window, &left_rect,
              &right_rect);
  const cv::Mat disparity = testing::computeDisparity(*stage.matcher, left_rect, right_rect);
  if (!o.debug_path.empty()) {
    cv::imwrite(o.debug_path, docking_perception::disparity::renderDebugImage(disparity, detection, 64.0));
  }
  if (!o.disparity_path.empty()) cv::imwrite(o.disparity_path, disparity);
}

/// The last frame's detection in full (frames from --left/--right).
void printDetectionDetails(const Options& o, const BenchRun& run) {
  const Detection& detection = run.detection;
  std::cout << std::setprecision(3) << "  detection on " << o.left_path << ": "
            << (detection.found ? "found" : "NOT found: " + detection.reason) << ", position ("
            << detection.position_m.x() << ", " << detection.position_m.y() << ", " << detection.position_m.z()
            << ") m, " << detection.blob_pixels << " px, thickness " << detection.blob_thickness_px << " px, "
            << detection.near_objects_skipped << " near objects skipped, " << detection.not_target_shaped_skipped
            << " not target-shaped; blob " << detection.shape.width_m << " x " << detection.shape.height_m
            << " m, fill " << detection.shape.fill << ", depth extent " << detection.shape.depth_extent_m
            << " m; footprint " << (detection.footprint_fitted ? "fitted" : "not fitted") << ", yaw "
            << detection.footprint_yaw_rad * 180.0 / 3.14159265358979 << " deg, on outline "
            << detection.footprint_inlier_fraction << "; appearance "
            << docking_perception::disparity::appearanceVerdictName(run.appearance.verdict) << " score "
            << run.appearance.score << "; outcome " << docking_perception::disparity::outcomeName(detection.outcome)
            << "\n";
}

/// The last frame's detection against the synthetic scene's truth.
void printDetectionAgainstTruth(const Detection& detection) {
  std::cout << std::setprecision(3) << "  detection: " << (detection.found ? "found" : "NOT found: " + detection.reason)
            << ", position (" << detection.position_m.x() << ", " << detection.position_m.y() << ", "
            << detection.position_m.z() << ") m, truth (" << kTruthX << ", " << kTruthY << ", " << kTruthZ << ") m\n";
}

}  // namespace

int main(int argc, char** argv) {
  Options o;
  if (!parseArguments(argc, argv, &o)) {
    std::cerr << kUsage;
    return 2;
  }
  cv::setNumThreads(1);
  try {
    BenchInputs in;
    if (!loadInputs(o, &in)) return 1;
    FarStage stage(o, in);
    BenchRun run = timeFrames(o, in, stage);
    if (!reportTimes(o, in, stage, run)) return 1;
    writeDebugOutputs(o, in, stage, run.detection);
    if (!o.left_path.empty()) {
      printDetectionDetails(o, run);
    } else {
      printDetectionAgainstTruth(run.detection);
    }
    std::cout << "  wrote " << o.output_path << "\n";
  } catch (const std::exception& error) {
    std::cerr << "bench_disparity: " << error.what() << "\n";
    return 1;
  }
  return 0;
}
