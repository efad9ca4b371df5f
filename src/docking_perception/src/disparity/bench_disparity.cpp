// bench_disparity: single-thread timing of the far-range pipeline on a fixed rendered 640x480 pair.
// A program that prints figures, never a test (timings depend on the machine and its load).
//
//   bench_disparity OUTPUT.json [--frames N] [--config-dir DIR]
//                   [--left RAW.png --right RAW.png] [--debug-image OUT.png]
//                   [--disparity-out OUT.tiff] [--scale S] [--disparity-range N]
//
// --scale 0.5 measures a far-range stage at half resolution (issue 15, not what perception.launch runs
// yet): the raw frames are rectified straight to the scaled size (the projection scaled), the matcher's
// window, search range and speckle size and the detector's pixel thresholds scaled with it (areas by
// S^2). --disparity-range overrides the matcher's range (after scaling; a multiple of 16).
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
#include "synthetic_stereo.h"

namespace {

using docking_perception::disparity::DisparityDetector;
using docking_perception::disparity::Detection;
using docking_perception::disparity::StereoGeometry;
namespace testing = docking_perception::disparity::testing;

const char* const kUsage =
    "usage: bench_disparity OUTPUT.json [--frames N] [--config-dir DIR] [--left RAW.png --right "
    "RAW.png] [--debug-image OUT.png] [--disparity-out OUT.tiff] [--scale S] [--disparity-range N]\n";

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

void rectifyMaps(const testing::CameraCalibration& calibration, cv::Size rectified_size, cv::Mat* map1,
                 cv::Mat* map2) {
  // image_geometry's rectification: fixed-point maps, bilinear remap (image_proc's default).
  cv::initUndistortRectifyMap(calibration.camera_matrix, calibration.distortion,
                              calibration.rectification, calibration.projection, rectified_size,
                              CV_16SC2, *map1, *map2);
}

// What image_proc does to each camera of the pair: bgr8 to grey (debayer's image_mono), then rectify.
// Not inlined: scripts/bench_instructions.py counts this step's instructions by its name under callgrind.
__attribute__((noinline)) void rectifyPair(const cv::Mat& left_raw, const cv::Mat& right_raw,
                                           const cv::Mat (&left_maps)[2], const cv::Mat (&right_maps)[2],
                                           cv::Mat* left_rect, cv::Mat* right_rect) {
  cv::Mat left_mono = left_raw, right_mono = right_raw;
  if (left_raw.channels() == 3) {
    cv::cvtColor(left_raw, left_mono, cv::COLOR_BGR2GRAY);
    cv::cvtColor(right_raw, right_mono, cv::COLOR_BGR2GRAY);
  }
  cv::remap(left_mono, *left_rect, left_maps[0], left_maps[1], cv::INTER_LINEAR);
  cv::remap(right_mono, *right_rect, right_maps[0], right_maps[1], cv::INTER_LINEAR);
}

// A calibration whose rectified image is `scale` times the size: the projection's pixel rows scaled (the
// raw image and its distortion stay as they are).
testing::CameraCalibration scaledRectification(testing::CameraCalibration calibration, double scale) {
  calibration.projection = calibration.projection.clone();
  calibration.projection.row(0) *= scale;
  calibration.projection.row(1) *= scale;
  return calibration;
}

// The matcher and detector for a disparity image `scale` times the size: lengths in pixels scaled,
// areas by scale^2, the window kept odd and >= 5, the search range a multiple of 16.
void scaleForResolution(double scale, testing::MatcherSettings* settings,
                        docking_perception::disparity::DetectorParams* params) {
  const auto scaled = [scale](double px) { return px * scale; };
  const auto area = [scale](double px2) { return static_cast<int>(std::lround(px2 * scale * scale)); };
  settings->correlation_window_size = std::max(5, static_cast<int>(std::lround(scaled(settings->correlation_window_size))) | 1);
  settings->min_disparity = static_cast<int>(std::lround(scaled(settings->min_disparity)));
  settings->disparity_range = std::max(16, static_cast<int>(std::lround(scaled(settings->disparity_range) / 16.0)) * 16);
  settings->speckle_size = area(settings->speckle_size);
  params->closest_min_pixels = area(params->closest_min_pixels);
  params->threshold_margin_px = scaled(params->threshold_margin_px);
  params->face_min_band_px = scaled(params->face_min_band_px);
  params->min_blob_area_px = area(params->min_blob_area_px);
  params->min_blob_thickness_px = scaled(params->min_blob_thickness_px);
  params->border_margin_px = std::max(1, static_cast<int>(std::lround(scaled(params->border_margin_px))));
  params->min_disparity_px = scaled(params->min_disparity_px);
  params->max_disparity_px = scaled(params->max_disparity_px);
  params->disparity_sigma_px = scaled(params->disparity_sigma_px);
  params->centre_sigma_px = scaled(params->centre_sigma_px);
  params->shape_tolerance_px = scaled(params->shape_tolerance_px);
}

}  // namespace

int main(int argc, char** argv) {
  std::string output_path, left_path, right_path, debug_path, disparity_path;
  std::string config_dir = DISPARITY_CONFIG_DIR;
  int frames = 100;
  double scale = 1.0;
  int disparity_range_override = 0;  // 0: the configured (scaled) range
  for (int i = 1; i < argc; ++i) {
    const std::string arg = argv[i];
    if (arg == "--frames" && i + 1 < argc) {
      frames = std::max(1, std::atoi(argv[++i]));
    } else if (arg == "--config-dir" && i + 1 < argc) {
      config_dir = argv[++i];
    } else if (arg == "--left" && i + 1 < argc) {
      left_path = argv[++i];
    } else if (arg == "--right" && i + 1 < argc) {
      right_path = argv[++i];
    } else if (arg == "--debug-image" && i + 1 < argc) {
      debug_path = argv[++i];
    } else if (arg == "--scale" && i + 1 < argc) {
      scale = std::atof(argv[++i]);
    } else if (arg == "--disparity-range" && i + 1 < argc) {
      disparity_range_override = std::atoi(argv[++i]);
    } else if (arg == "--disparity-out" && i + 1 < argc) {
      disparity_path = argv[++i];  // float disparity of the last frame, px, for offline analysis
    } else if (!arg.empty() && arg[0] != '-' && output_path.empty()) {
      output_path = arg;
    } else {
      std::cerr << kUsage;
      return 2;
    }
  }
  if (output_path.empty() || left_path.empty() != right_path.empty() || !(scale > 0.1 && scale <= 1.0) ||
      disparity_range_override % 16 != 0 || disparity_range_override < 0) {
    std::cerr << kUsage;
    return 2;
  }

  cv::setNumThreads(1);
  try {
    const auto left_calibration = testing::loadCameraCalibration(config_dir + "/cameras/stereo_left.yaml");
    const auto right_calibration =
        testing::loadCameraCalibration(config_dir + "/cameras/stereo_right.yaml");
    auto settings = testing::loadMatcherSettings(config_dir + "/stereo_image_proc.yaml");
    auto params = testing::loadDetectorParams(config_dir + "/disparity_detector.yaml");
    params.target_shape =
        docking_perception::disparity::loadTargetShape(config_dir + "/target.yaml");
    if (scale != 1.0) scaleForResolution(scale, &settings, &params);
    if (disparity_range_override > 0) settings.disparity_range = disparity_range_override;
    const cv::Size rectified_size(static_cast<int>(std::lround(left_calibration.size.width * scale)),
                                  static_cast<int>(std::lround(left_calibration.size.height * scale)));

    // The fixed scene: the target face-on at 3 m, slightly off-axis, floor and a wall at 8 m.
    const double truth_x = 0.3, truth_y = 0.0, truth_z = 3.0;
    testing::SyntheticScene scene = testing::targetScene(truth_x, truth_y, truth_z, 8.0);
    scene.focal_px = left_calibration.projection.at<double>(0, 0);
    scene.cx_px = left_calibration.projection.at<double>(0, 2);
    scene.cy_px = left_calibration.projection.at<double>(1, 2);
    scene.baseline_m = -right_calibration.projection.at<double>(0, 3) /
                       right_calibration.projection.at<double>(0, 0);
    cv::Mat left_rectified_truth, right_rectified_truth;
    testing::renderStereoPair(scene, &left_rectified_truth, &right_rectified_truth);
    cv::Mat left_raw = distort(left_rectified_truth, left_calibration);
    cv::Mat right_raw = distort(right_rectified_truth, right_calibration);
    if (!left_path.empty()) {
      // As published (the simulator's cameras are bgr8): image_proc rectifies all channels.
      left_raw = cv::imread(left_path, cv::IMREAD_UNCHANGED);
      right_raw = cv::imread(right_path, cv::IMREAD_UNCHANGED);
      if (left_raw.empty() || right_raw.empty()) {
        std::cerr << "bench_disparity: cannot read " << (left_raw.empty() ? left_path : right_path)
                  << "\n";
        return 1;
      }
      if (left_raw.size() != left_calibration.size || right_raw.size() != right_calibration.size) {
        std::cerr << "bench_disparity: frame size differs from the calibration's "
                  << left_calibration.size << "\n";
        return 1;
      }
    }

    cv::Mat left_maps[2], right_maps[2];
    rectifyMaps(scaledRectification(left_calibration, scale), rectified_size, &left_maps[0], &left_maps[1]);
    rectifyMaps(scaledRectification(right_calibration, scale), rectified_size, &right_maps[0], &right_maps[1]);
    auto matcher = testing::createMatcher(settings);
    const DisparityDetector detector(params);
    StereoGeometry geometry = testing::geometryOf(scene);
    geometry.focal_px *= scale;
    geometry.cx_px *= scale;
    geometry.cy_px *= scale;
    const int range = (settings.disparity_range / 16) * 16;
    const cv::Rect valid_region = testing::matcherValidRegion(settings, rectified_size);

    // CPU time of this thread: on a shared machine, wall time measures the other users too.
    struct Clock {
      static double now() {
        timespec ts{};
        clock_gettime(CLOCK_THREAD_CPUTIME_ID, &ts);
        return ts.tv_sec * 1e3 + ts.tv_nsec * 1e-6;
      }
    };
    auto ms_since = [](double start_ms) { return Clock::now() - start_ms; };
    const auto wall_start = std::chrono::steady_clock::now();
    std::map<std::string, std::vector<double>> samples;
    Detection detection;
    const int warmup = 3;
    for (int frame = 0; frame < frames + warmup; ++frame) {
      const auto start = Clock::now();
      cv::Mat left_rect, right_rect;
      rectifyPair(left_raw, right_raw, left_maps, right_maps, &left_rect, &right_rect);
      const double rectify_ms = ms_since(start);
      const auto disparity_start = Clock::now();
      const cv::Mat disparity = testing::computeDisparity(*matcher, left_rect, right_rect);
      const double disparity_ms = ms_since(disparity_start);
      const auto detection_start = Clock::now();
      detection = detector.detect(disparity, geometry, settings.min_disparity,
                                  testing::maxDisparity(settings), valid_region);
      const double detection_ms = ms_since(detection_start);
      const double total_ms = ms_since(start);
      if (frame < warmup) continue;
      samples["rectify"].push_back(rectify_ms);
      samples["disparity"].push_back(disparity_ms);
      samples["detection"].push_back(detection_ms);
      samples["disparity_total"].push_back(total_ms);
    }

    const double wall_ms = std::chrono::duration<double, std::milli>(
                               std::chrono::steady_clock::now() - wall_start).count() /
                           (frames + warmup);
    double cpu_total_ms = 0.0;
    for (double ms : samples["disparity_total"]) cpu_total_ms += ms;
    std::cout << "bench_disparity: " << (left_path.empty() ? "synthetic grey pair" : left_path)
              << ", " << rectified_size.width << "x" << rectified_size.height << " (scale " << scale
              << "), 1 thread, " << frames << " frames, matcher "
              << (settings.stereo_algorithm == 0 ? "StereoBM" : "StereoSGBM") << " range " << range
              << " window " << (settings.correlation_window_size | 1) << "\n";
    std::ofstream json(output_path);
    if (!json) {
      std::cerr << "bench_disparity: cannot write " << output_path << "\n";
      return 1;
    }
    json << std::fixed << std::setprecision(3);
    json << "{\"image\": \"" << rectified_size.width << "x" << rectified_size.height
         << "\", \"threads\": 1, \"stages\": {";
    bool first = true;
    for (const char* stage : {"rectify", "disparity", "detection", "disparity_total"}) {
      const double ms = medianOf(samples[stage]);
      const double hz = ms > 0.0 ? 1000.0 / ms : 0.0;
      std::cout << "  " << std::left << std::setw(16) << stage << std::right << std::fixed
                << std::setprecision(2) << std::setw(8) << ms << " ms median  " << std::setw(8)
                << hz << " Hz\n";
      json << (first ? "" : ", ") << "\"" << stage << "\": {\"ms_median\": " << ms
           << ", \"hz\": " << hz << "}";
      first = false;
    }
    json << "}}\n";
    std::cout << std::setprecision(2) << "  (thread CPU time; wall time per frame " << wall_ms
              << " ms against " << cpu_total_ms / frames
              << " ms CPU: the difference is other load on the machine)\n";
    if (!debug_path.empty() || !disparity_path.empty()) {
      cv::Mat left_rect, right_rect;
      rectifyPair(left_raw, right_raw, left_maps, right_maps, &left_rect, &right_rect);
      const cv::Mat disparity = testing::computeDisparity(*matcher, left_rect, right_rect);
      if (!debug_path.empty()) {
        cv::imwrite(debug_path,
                    docking_perception::disparity::renderDebugImage(disparity, detection, 64.0));
      }
      if (!disparity_path.empty()) cv::imwrite(disparity_path, disparity);
    }
    if (!left_path.empty()) {
      std::cout << std::setprecision(3) << "  detection on " << left_path << ": "
                << (detection.found ? "found" : "NOT found: " + detection.reason) << ", position ("
                << detection.position_m.x() << ", " << detection.position_m.y() << ", "
                << detection.position_m.z() << ") m, " << detection.blob_pixels << " px, thickness "
                << detection.blob_thickness_px << " px, " << detection.near_objects_skipped
                << " near objects skipped, " << detection.not_target_shaped_skipped
                << " not target-shaped; blob " << detection.shape.width_m << " x "
                << detection.shape.height_m << " m, fill " << detection.shape.fill << ", depth extent "
                << detection.shape.depth_extent_m << " m; outcome "
                << docking_perception::disparity::outcomeName(detection.outcome) << "\n";
      std::cout << "  wrote " << output_path << "\n";
      return 0;
    }
    std::cout << std::setprecision(3) << "  detection: "
              << (detection.found ? "found" : "NOT found: " + detection.reason) << ", position ("
              << detection.position_m.x() << ", " << detection.position_m.y() << ", "
              << detection.position_m.z() << ") m, truth (" << truth_x << ", " << truth_y << ", "
              << truth_z << ") m\n"
              << "  wrote " << output_path << "\n";
  } catch (const std::exception& error) {
    std::cerr << "bench_disparity: " << error.what() << "\n";
    return 1;
  }
  return 0;
}
