// pipeline_on_frames: perception.launch's image path offline, on raw camera frames as the cameras (or
// the simulator) publish them: image_proc's debayer (bgr8 -> mono8) and rectify (bilinear remap),
// stereo_image_proc's disparity with config/stereo_image_proc.yaml, then the disparity detector and the
// two mono_pose instances (visible on the rectified left image, IR on the rectified IR image), each
// with its config file. Writes one JSON line per frame with every estimate. For comparing the same
// frames before and after a lossy step (scripts/eval/transport_cost.py: JPEG over the network link).
//
//   pipeline_on_frames --config DIR --dt S FRAME_PREFIX...
//
// FRAME_PREFIX: files PREFIX_stereo_left.png, PREFIX_stereo_right.png, PREFIX_ir.png (sim_render's
// names); frames are processed in the given order, stamped 0, dt, 2 dt, ... (mono_pose tracks between
// frames). One thread. The detector's search band and valid region follow the matcher settings
// (as the synthetic-pair tests do), not a DisparityImage message.
#include <opencv2/calib3d.hpp>
#include <opencv2/core/utility.hpp>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

#include <cmath>
#include <cstdio>
#include <iostream>
#include <memory>
#include <string>
#include <vector>

#include "docking_perception/disparity/disparity_detector.h"
#include "docking_perception/mono/mono_pose_estimator.h"
#include "docking_settings/yaml_loader.h"
#include "synthetic_stereo.h"

namespace dp = docking_perception;
namespace dt = docking_perception::disparity::testing;

namespace {

struct Rectifier {
  cv::Mat map1, map2;
  dp::mono::CameraIntrinsics intrinsics;  // of the rectified image (P)

  explicit Rectifier(const dt::CameraCalibration& cal) {
    cv::initUndistortRectifyMap(cal.camera_matrix, cal.distortion, cal.rectification,
                                cal.projection(cv::Rect(0, 0, 3, 3)), cal.size, CV_16SC2, map1, map2);
    intrinsics.fx = cal.projection.at<double>(0, 0);
    intrinsics.fy = cal.projection.at<double>(1, 1);
    intrinsics.cx = cal.projection.at<double>(0, 2);
    intrinsics.cy = cal.projection.at<double>(1, 2);
    intrinsics.width = cal.size.width;
    intrinsics.height = cal.size.height;
  }
  // image_proc: debayer to grey (a bgr8 camera image -> mono8 with cvtColor), then rectify.
  cv::Mat operator()(const cv::Mat& raw) const {
    cv::Mat grey, rect;
    if (raw.channels() == 3) cv::cvtColor(raw, grey, cv::COLOR_BGR2GRAY);
    else grey = raw;
    cv::remap(grey, rect, map1, map2, cv::INTER_LINEAR);
    return rect;
  }
};

std::string num(double v) {
  if (!std::isfinite(v)) return "null";
  char buf[32];
  std::snprintf(buf, sizeof(buf), "%.9g", v);
  return buf;
}

std::string jsonString(const std::string& s) {
  std::string out = "\"";
  for (char c : s) {
    if (c == '"' || c == '\\') out += '\\';
    out += (c == '\n' ? ' ' : c);
  }
  return out + "\"";
}

std::string monoJson(const dp::mono::MonoPoseResult& r) {
  std::string s = "{\"valid\": " + std::string(r.valid ? "true" : "false");
  if (r.valid) {
    const Eigen::Vector3d& t = r.pose.translation;
    const Eigen::Quaterniond q(r.pose.rotation);
    s += ", \"position_m\": [" + num(t.x()) + ", " + num(t.y()) + ", " + num(t.z()) + "]";
    s += ", \"quaternion_xyzw\": [" + num(q.x()) + ", " + num(q.y()) + ", " + num(q.z()) + ", " + num(q.w()) + "]";
  } else {
    s += ", \"status\": " + jsonString(r.status);
  }
  return s + "}";
}

int usage() {
  std::cerr << "usage: pipeline_on_frames --config DIR [--dt S] FRAME_PREFIX...\n";
  return 2;
}

std::string disparityJson(const dp::disparity::Detection& d) {
  std::string s = "{\"valid\": " + std::string(d.found ? "true" : "false");
  if (d.found)
    s += ", \"position_m\": [" + num(d.position_m.x()) + ", " + num(d.position_m.y()) + ", " + num(d.position_m.z()) +
         "]";
  else
    s += ", \"status\": " + jsonString(dp::disparity::outcomeName(d.outcome));
  return s + "}";
}

/// perception.launch's image path, each stage with its shipped configuration from the config folder.
class Pipeline {
 public:
  explicit Pipeline(const std::string& config)
      : left_cal_(dt::loadCameraCalibration(config + "/cameras/stereo_left.yaml")),
        right_cal_(dt::loadCameraCalibration(config + "/cameras/stereo_right.yaml")),
        ir_cal_(dt::loadCameraCalibration(config + "/cameras/ir.yaml")),
        left_rect_(left_cal_),
        right_rect_(right_cal_),
        ir_rect_(ir_cal_),
        matcher_settings_(dt::loadMatcherSettings(config + "/stereo_image_proc.yaml")),
        matcher_(dt::createMatcher(matcher_settings_)),
        detector_(dt::shippedDetectorSettings(config).detector,
                  dp::disparity::loadTargetShape(config + "/target.yaml"), dt::shippedRig(config)) {
    geometry_.focal_px = left_rect_.intrinsics.fx;
    geometry_.cx_px = left_rect_.intrinsics.cx;
    geometry_.cy_px = left_rect_.intrinsics.cy;
    geometry_.baseline_m = -right_cal_.projection.at<double>(0, 3) / right_cal_.projection.at<double>(0, 0);
    const dp::mono::TargetModel model = dp::mono::TargetModel::loadFromYaml(config + "/target.yaml");
    const char* mono_files[2] = {"/mono_pose_visible.yaml", "/mono_pose_ir.yaml"};
    const Rectifier* mono_rect[2] = {&left_rect_, &ir_rect_};
    for (int m = 0; m < 2; ++m) {
      const dp::mono::MonoPoseParams params =
          docking_settings::shippedSettings<dp::mono::MonoPoseNodeSettings>(config + mono_files[m]).core;
      mono_[m] = std::make_unique<dp::mono::MonoPoseEstimator>(model, mono_rect[m]->intrinsics, params);
    }
  }

  /// One frame's JSON line: rectify, disparity and the detector, both mono_pose instances.
  std::string process(const std::string& prefix, const cv::Mat& left, const cv::Mat& right, const cv::Mat& ir,
                      double stamp) {
    const cv::Mat l = left_rect_(left), r = right_rect_(right), i = ir_rect_(ir);
    const cv::Mat disparity = dt::computeDisparity(*matcher_, l, r);
    const dp::disparity::Detection d =
        detector_.detect(disparity, geometry_, matcher_settings_.min_disparity, dt::maxDisparity(matcher_settings_),
                         dt::matcherValidRegion(matcher_settings_, disparity.size()));
    std::string line = "{\"frame\": " + jsonString(prefix) + ", \"stamp_s\": " + num(stamp) +
                       ", \"disparity\": " + disparityJson(d);
    line += ", \"mono_visible\": " + monoJson(mono_[0]->process(l, stamp));
    line += ", \"mono_ir\": " + monoJson(mono_[1]->process(i, stamp)) + "}";
    return line;
  }

 private:
  const dt::CameraCalibration left_cal_, right_cal_, ir_cal_;
  const Rectifier left_rect_, right_rect_, ir_rect_;
  const dt::MatcherSettings matcher_settings_;
  cv::Ptr<cv::StereoMatcher> matcher_;
  const dp::disparity::DisparityDetector detector_;
  dp::disparity::StereoGeometry geometry_;
  std::unique_ptr<dp::mono::MonoPoseEstimator> mono_[2];
};

}  // namespace

int main(int argc, char** argv) {
  std::string config;
  double dt_s = 1.0 / 15.0;
  std::vector<std::string> prefixes;
  for (int i = 1; i < argc; ++i) {
    const std::string arg = argv[i];
    if (arg.rfind("--", 0) != 0) {
      prefixes.push_back(arg);
    } else if (i + 1 < argc && arg == "--config") {
      config = argv[++i];
    } else if (i + 1 < argc && arg == "--dt") {
      dt_s = std::stod(argv[++i]);
    } else {
      return usage();
    }
  }
  if (config.empty() || prefixes.empty() || !(dt_s > 0.0)) return usage();
  cv::setNumThreads(1);
  try {
    Pipeline pipeline(config);
    for (std::size_t k = 0; k < prefixes.size(); ++k) {
      const std::string& p = prefixes[k];
      const cv::Mat left = cv::imread(p + "_stereo_left.png", cv::IMREAD_UNCHANGED);
      const cv::Mat right = cv::imread(p + "_stereo_right.png", cv::IMREAD_UNCHANGED);
      const cv::Mat ir = cv::imread(p + "_ir.png", cv::IMREAD_UNCHANGED);
      if (left.empty() || right.empty() || ir.empty()) {
        std::cerr << p << "_{stereo_left,stereo_right,ir}.png: missing or unreadable\n";
        return 1;
      }
      std::cout << pipeline.process(p, left, right, ir, static_cast<double>(k) * dt_s) << std::endl;
    }
  } catch (const std::exception& e) {
    std::cerr << "pipeline_on_frames: " << e.what() << "\n";
    return 1;
  }
  return 0;
}
