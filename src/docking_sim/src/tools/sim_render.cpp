// Renders the simulator's cameras without ROS: saves frames as PNG, renders a sequence with its ground
// truth (for offline evaluation), or benchmarks the renderer.
//
//   sim_render --config DIR --scenario NAME [--time S] [--out PREFIX]     save PREFIX_{stereo_left,...}.png
//   sim_render --config DIR --scenario NAME --bench N                      CPU ms per frame, per camera
//   sim_render --config DIR --scenario NAME --sequence N [--dt S] [--time T0] [--camera C] --out FOLDER
//       N frames of camera C (stereo_left, the default, or ir) at T0, T0 + dt, ... as its mono_pose instance
//       sees them (image_rect: grey, rectified): FOLDER/left_rect_NNNN.png (ir: ir_rect_NNNN.png) and FOLDER/sequence.json
//       (intrinsics of the rectified image, and per frame the stamp, the pose of the docking port in the
//       rectified optical frame and its linear and angular velocity in that frame).
//   sim_render --config DIR --scenario NAME --approach FILE --out FOLDER
//       the three raw cameras (as the camera nodes would publish them) with the chaser on the docking port's
//       axis, facing the port, at the distances of FILE: one line "t_s distance_m" per frame (base_link to
//       the port centre; the scene at sim time t_s): FOLDER/frame_NNNN_{stereo_left,stereo_right,ir}.png
//       (robot.launch's bench frames: src/docking_sim/scripts/render_bench_frames)
//   --target FILE   another target model instead of DIR/target.yaml (e.g. config/target_tagged.yaml)
//
// DIR is the workspace's config folder (sim.yaml, target.yaml, robot.yaml, omni_base.yaml, scenarios/).
#include <opencv2/calib3d.hpp>
#include <opencv2/core/utility.hpp>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

#include <chrono>
#include <cmath>
#include <cstdio>
#include <ctime>
#include <fstream>
#include <iostream>
#include <sstream>
#include <string>
#include <sys/stat.h>

#include <yaml-cpp/yaml.h>

#include "docking_sim/config_error.h"
#include "docking_sim/simulation.h"

namespace {

double cpuSeconds() {
  timespec ts{};
  clock_gettime(CLOCK_PROCESS_CPUTIME_ID, &ts);
  return static_cast<double>(ts.tv_sec) + 1e-9 * static_cast<double>(ts.tv_nsec);
}

int usage() {
  std::cerr << "usage: sim_render --config DIR --scenario NAME [--target FILE] [--time S] [--out PREFIX] [--bench N]\n"
               "       sim_render --config DIR --scenario NAME [--target FILE] --sequence N [--dt S] [--time T0] "
               "[--camera stereo_left|ir] --out FOLDER\n"
               "       sim_render --config DIR --scenario NAME [--target FILE] --approach FILE --out FOLDER\n";
  return 2;
}

/// --approach: the three raw cameras with the chaser on the port axis at each line's distance (see the top).
int renderApproach(docking_sim::Simulation& sim, const std::string& path_file, const std::string& folder) {
  std::ifstream lines(path_file);
  if (!lines) {
    std::cerr << "cannot read " << path_file << "\n";
    return 1;
  }
  ::mkdir(folder.c_str(), 0755);
  const char* names[3] = {"stereo_left", "stereo_right", "ir"};
  double t_s = 0.0, distance_m = 0.0;
  int frame = 0;
  while (lines >> t_s >> distance_m) {
    if (!(t_s >= sim.time() - 1e-9) || !(distance_m > 0.0)) {
      std::cerr << path_file << ": line " << frame + 1 << ": times must not decrease and distances be positive\n";
      return 1;
    }
    if (t_s > sim.time()) sim.advance(t_s - sim.time());
    const Eigen::Isometry3d port = sim.worldTPort();
    const Eigen::Vector3d axis = port.linear().col(0);  // x out of the port face
    const Eigen::Vector3d base = port.translation() + distance_m * axis;
    sim.placeChaser(omni_base::Pose2D{base.x(), base.y(), std::atan2(-axis.y(), -axis.x())});
    const auto images = sim.renderCameras({{true, true, true}}, sim.settings().render_threads);
    for (int cam = 0; cam < 3; ++cam) {
      char name[64];
      std::snprintf(name, sizeof(name), "/frame_%04d_%s.png", frame, names[cam]);
      if (!cv::imwrite(folder + name, *images[static_cast<std::size_t>(cam)])) {
        std::cerr << "cannot write " << folder << name << "\n";
        return 1;
      }
    }
    ++frame;
  }
  std::cout << "rendered " << frame << " frames of the approach to " << folder << "\n";
  return frame > 0 ? 0 : 1;
}

std::string num(double v) {
  char buf[32];
  std::snprintf(buf, sizeof(buf), "%.12g", v);
  return buf;
}

template <typename Vec>
std::string jsonArray(const Vec& v, int n) {
  std::string s = "[";
  for (int i = 0; i < n; ++i) s += (i ? ", " : "") + num(v[i]);
  return s + "]";
}

std::string jsonString(const std::string& s) {
  std::string out = "\"";
  for (char c : s) {
    if (c == '"' || c == '\\') out += '\\';
    out += c;
  }
  return out + "\"";
}

/// What blur and exposure the target gets in camera `cam`'s last frame: the port's depth, the
/// defocus sigma there (thin lens), the residual lens blur, the largest displacement of the face's
/// corners over the exposure (motion blur length), the exposure, gain and effective noise.
struct TargetBlur {
  double depth_m{0}, defocus_sigma_px{0}, residual_sigma_px{0}, motion_px{0};
  double total_sigma_px{0};   ///< sqrt(defocus^2 + residual^2 + (motion / sqrt 12)^2): the Gaussian-equivalent
};

TargetBlur targetBlur(const docking_sim::Simulation& sim, int cam) {
  const auto& renderer = sim.renderer(cam);
  const auto& e = renderer.effects();
  const double exposure = renderer.lastExposure().exposure_time_s;
  const auto& K = sim.robot().cameras[static_cast<std::size_t>(cam)].calibration.K;
  const auto& target = sim.target();
  TargetBlur b;
  b.depth_m = (sim.worldTCamera(cam).inverse() * sim.worldTPort()).translation().z();
  b.defocus_sigma_px = docking_sim::defocusSigmaPx(e, b.depth_m);
  b.residual_sigma_px = e.blur_sigma_px;
  if (e.motion_blur_enabled) {
    for (int corner = 0; corner < 4; ++corner) {
      const Eigen::Vector3d local(0.0, (corner & 1 ? 0.5 : -0.5) * target.face_width_m,
                                  (corner & 2 ? 0.5 : -0.5) * target.face_height_m);
      Eigen::Vector2d q[2];
      for (int end = 0; end < 2; ++end) {
        const double dt = (end - 0.5) * exposure;
        const Eigen::Vector3d p = sim.worldTCameraAt(cam, dt).inverse() *
                                  (sim.worldTTargetRobotAt(sim.time() + dt) * target.robot_T_port * local);
        q[end] = Eigen::Vector2d(K(0, 0) * p.x() / p.z(), K(1, 1) * p.y() / p.z());
      }
      b.motion_px = std::max(b.motion_px, (q[1] - q[0]).norm());
    }
  }
  b.total_sigma_px = std::sqrt(b.defocus_sigma_px * b.defocus_sigma_px + b.residual_sigma_px * b.residual_sigma_px +
                               b.motion_px * b.motion_px / 12.0);
  return b;
}

std::string describe(const docking_sim::Simulation& sim, int cam) {
  const TargetBlur b = targetBlur(sim, cam);
  const auto& x = sim.renderer(cam).lastExposure();
  const auto& lighting = sim.renderer(cam).band() == docking_sim::Band::kVisible ? sim.lighting().visible
                                                                                 : sim.lighting().ir;
  char buf[400];
  std::snprintf(buf, sizeof(buf),
                "target at %.2f m: defocus sigma %.2f px, residual %.2f px, motion %.1f px over the exposure "
                "(total Gaussian-equivalent %.2f px); exposure %.1f ms, gain %.2f, noise sigma %.1f DN, mean %.0f, "
                "%d sub-frames (scene motion %.1f px)",
                b.depth_m, b.defocus_sigma_px, b.residual_sigma_px, b.motion_px, b.total_sigma_px,
                1e3 * x.exposure_time_s, x.gain, lighting.noise_sigma * x.gain, x.measured_mean, x.subframes,
                x.motion_px);
  return buf;
}

/// R: the rectification rotation (rectified <- raw optical frame), from the calibration file (the loader
/// keeps K, D, P only). False (reported) when the file's rectification_matrix does not parse.
bool loadRectification(const docking_sim::CameraCalibration& cal, cv::Matx33d* rect_R) {
  *rect_R = cv::Matx33d::eye();
  try {
    const YAML::Node r = YAML::LoadFile(cal.file)["rectification_matrix"]["data"];
    if (r && r.IsSequence() && r.size() == 9)
      for (int i = 0; i < 9; ++i) (*rect_R)(i / 3, i % 3) = r[static_cast<std::size_t>(i)].as<double>();
  } catch (const YAML::Exception& e) {
    std::cerr << cal.file << ": rectification_matrix: " << e.what() << "\n";
    return false;
  }
  return true;
}

/// sequence.json up to the frames list: scenario, target, camera, the rectified intrinsics new_K, dt.
void writeSequenceHeader(std::ostringstream& json, const std::string& scenario, const std::string& target_file,
                         const std::string& camera_name, const docking_sim::CameraCalibration& cal,
                         const cv::Matx33d& new_K, double dt_s) {
  json << "{\n  \"scenario\": " << jsonString(scenario) << ",\n  \"target\": " << jsonString(target_file)
       << ",\n  \"camera\": " << jsonString(camera_name) << ",\n"
       << "  \"rectification\": \"rendered with the calibration's plumb_bob distortion, converted to grey and "
          "rectified with cv::initUndistortRectifyMap(K, D, R, P) + bilinear cv::remap, as image_proc does\",\n"
       << "  \"frame_id\": " << jsonString(camera_name + "_optical_frame") << ",\n"
       << "  \"intrinsics\": {\"width\": " << cal.width << ", \"height\": " << cal.height << ", \"fx\": "
       << num(new_K(0, 0)) << ", \"fy\": " << num(new_K(1, 1)) << ", \"cx\": " << num(new_K(0, 2))
       << ", \"cy\": " << num(new_K(1, 2)) << "},\n"
       << "  \"dt_s\": " << num(dt_s) << ",\n  \"frames\": [\n";
}

/// One frame's entry of sequence.json (without the separator): stamp, image, the truth in the rectified
/// frame (R_rect), the target's blur and the exposure.
void writeSequenceFrame(std::ostringstream& json, const docking_sim::Simulation& sim, int cam, int k,
                        const char* name, const Eigen::Matrix3d& R_rect) {
  const docking_sim::RelativeTruth truth = sim.truthInCamera(cam);
  const Eigen::Matrix3d R = R_rect * truth.camera_T_port.linear();
  const Eigen::Vector3d t = R_rect * truth.camera_T_port.translation();
  const Eigen::Quaterniond q(R);
  const Eigen::Vector3d v = R_rect * truth.linear_m_s, w = R_rect * truth.angular_rad_s;
  Eigen::Matrix<double, 9, 1> r9;
  for (int i = 0; i < 3; ++i)
    for (int j = 0; j < 3; ++j) r9(3 * i + j) = R(i, j);
  json << "    {\"index\": " << k << ", \"stamp_s\": " << num(sim.time()) << ", \"image\": \"" << name
       << "\", \"position_m\": " << jsonArray(t, 3) << ", \"rotation\": " << jsonArray(r9, 9)
       << ", \"quaternion_xyzw\": [" << num(q.x()) << ", " << num(q.y()) << ", " << num(q.z()) << ", "
       << num(q.w()) << "], \"linear_m_s\": " << jsonArray(v, 3) << ", \"angular_rad_s\": " << jsonArray(w, 3);
  const TargetBlur blur = targetBlur(sim, cam);
  const auto& exposure = sim.renderer(cam).lastExposure();
  json << ", \"defocus_sigma_px\": " << num(blur.defocus_sigma_px) << ", \"motion_blur_px\": " << num(blur.motion_px)
       << ", \"exposure_s\": " << num(exposure.exposure_time_s) << ", \"gain\": " << num(exposure.gain) << "}";
}

/// The sequence mode: one camera's frames rectified as image_proc does it on the robot
/// (image_proc/debayer: bgr8 -> mono8 with cvtColor; image_proc/rectify: cv::remap of the
/// initUndistortRectifyMap(K, D, R, P) maps, bilinear), with the truth in the rectified frame.
int renderSequence(docking_sim::Simulation& sim, const std::string& scenario, const std::string& target_file,
                   int cam, int frames, double dt_s, const std::string& folder) {
  const bool ir = cam == docking_sim::RobotModel::kIr;
  const std::string camera_name = ir ? "ir" : "stereo_left";
  const char* file_prefix = ir ? "ir" : "left";
  const docking_sim::CameraCalibration& cal = sim.robot().cameras[cam].calibration;
  // P's left 3x3: the rectified intrinsics. Our left and IR cameras have R = I, P = K.
  cv::Matx33d rect_R;
  if (!loadRectification(cal, &rect_R)) return 1;
  const cv::Matx33d new_K(cal.P(0, 0), cal.P(0, 1), cal.P(0, 2), cal.P(1, 0), cal.P(1, 1), cal.P(1, 2), 0, 0, 1);
  cv::Mat map1, map2;
  cv::initUndistortRectifyMap(cal.K, cal.D, rect_R, new_K, cv::Size(cal.width, cal.height), CV_16SC2, map1, map2);
  ::mkdir(folder.c_str(), 0755);
  std::ostringstream json;
  writeSequenceHeader(json, scenario, target_file, camera_name, cal, new_K, dt_s);
  Eigen::Matrix3d R_rect;
  for (int i = 0; i < 3; ++i)
    for (int j = 0; j < 3; ++j) R_rect(i, j) = rect_R(i, j);
  cv::Mat gray, rect;
  for (int k = 0; k < frames; ++k) {
    if (k > 0) sim.advance(dt_s);
    const cv::Mat& raw = sim.render(cam);
    if (raw.channels() == 3) cv::cvtColor(raw, gray, cv::COLOR_BGR2GRAY);
    else gray = raw;
    cv::remap(gray, rect, map1, map2, cv::INTER_LINEAR);
    char name[64];
    std::snprintf(name, sizeof(name), "%s_rect_%04d.png", file_prefix, k);
    if (!cv::imwrite(folder + "/" + name, rect)) {
      std::cerr << "cannot write " << folder << "/" << name << "\n";
      return 1;
    }
    writeSequenceFrame(json, sim, cam, k, name, R_rect);
    json << (k + 1 < frames ? "," : "") << "\n";
  }
  json << "  ]\n}\n";
  std::ofstream file(folder + "/sequence.json");
  file << json.str();
  if (!file) {
    std::cerr << "cannot write " << folder << "/sequence.json\n";
    return 1;
  }
  std::cout << "wrote " << frames << " frames and " << folder << "/sequence.json\n";
  return 0;
}

const char* const kCameraNames[3] = {"stereo_left", "stereo_right", "ir"};

/// --bench: CPU ms per frame per camera (with its stages), then the three cameras of an instant together
/// on 1 and on render_threads threads (as the node renders them: Simulation::renderCameras).
void runBench(docking_sim::Simulation& sim, const std::string& scenario, int bench) {
  std::cout << "scenario " << scenario << ", " << bench << " frames per camera, 640x480\n";
  double total = 0.0;
  for (int cam = 0; cam < 3; ++cam) {
    sim.render(cam);  // warm-up: first-touch allocations
    docking_sim::RenderTiming stages;
    const double start = cpuSeconds();
    for (int k = 0; k < bench; ++k) {
      sim.advance(1.0 / 30.0);
      sim.render(cam);
      const auto& t = sim.renderer(cam).lastTiming();
      stages.rasterize_ms += t.rasterize_ms / bench;
      stages.defocus_ms += t.defocus_ms / bench;
      stages.distort_ms += t.distort_ms / bench;
      stages.effects_ms += t.effects_ms / bench;
    }
    const double ms = 1e3 * (cpuSeconds() - start) / bench;
    total += ms;
    std::cout << "  " << kCameraNames[cam] << ": " << ms << " ms CPU per frame (rasterize incl. sub-frames "
              << stages.rasterize_ms << ", defocus " << stages.defocus_ms << ", distortion " << stages.distort_ms
              << ", blur/glare/vignette/noise/metering " << stages.effects_ms << "); last frame "
              << sim.renderer(cam).lastExposure().subframes << " sub-frame(s)\n";
  }
  std::cout << "  mean over cameras: " << total / 3 << " ms CPU per frame\n";
  for (int threads : {1, sim.settings().render_threads}) {
    const auto start = std::chrono::steady_clock::now();
    for (int k = 0; k < bench; ++k) {
      sim.advance(1.0 / 30.0);
      sim.renderCameras({{true, true, true}}, threads);
    }
    const std::chrono::duration<double, std::milli> wall = std::chrono::steady_clock::now() - start;
    std::cout << "  three cameras on " << threads << " thread(s): " << wall.count() / bench
              << " ms wall per instant\n";
    if (threads == sim.settings().render_threads) break;
  }
}

struct Arguments {
  std::string config_dir, scenario = "default", out = "frame", target_file, approach_file;
  double time_s = 0.0, dt_s = 1.0 / 30.0;
  int bench = 0, sequence = 0, sequence_camera = docking_sim::RobotModel::kStereoLeft;
};

/// False on a malformed command line (then usage()).
bool parseArguments(int argc, char** argv, Arguments* a) {
  for (int i = 1; i < argc; ++i) {
    const std::string arg = argv[i];
    if (i + 1 >= argc) return false;
    const std::string value = argv[++i];
    if (arg == "--config") a->config_dir = value;
    else if (arg == "--scenario") a->scenario = value;
    else if (arg == "--time") a->time_s = std::stod(value);
    else if (arg == "--out") a->out = value;
    else if (arg == "--bench") a->bench = std::stoi(value);
    else if (arg == "--sequence") a->sequence = std::stoi(value);
    else if (arg == "--dt") a->dt_s = std::stod(value);
    else if (arg == "--target") a->target_file = value;
    else if (arg == "--approach") a->approach_file = value;
    else if (arg == "--camera" && (value == "stereo_left" || value == "ir"))
      a->sequence_camera = value == "ir" ? docking_sim::RobotModel::kIr : docking_sim::RobotModel::kStereoLeft;
    else return false;
  }
  return !a->config_dir.empty() && a->sequence >= 0 && a->dt_s > 0.0;
}

}  // namespace

int main(int argc, char** argv) {
  Arguments a;
  if (!parseArguments(argc, argv, &a)) return usage();
  docking_sim::SimulationFiles files;
  files.sim_config = a.config_dir + "/sim.yaml";
  files.scenario = a.config_dir + "/scenarios/" + a.scenario + ".yaml";
  files.target_config = a.target_file.empty() ? a.config_dir + "/target.yaml" : a.target_file;
  files.robot_config = a.config_dir + "/robot.yaml";
  files.omni_base_config = a.config_dir + "/omni_base.yaml";
  // One core, as the node runs: OpenCV's worker threads would only add hand-over cost here.
  cv::setNumThreads(1);
  try {
    docking_sim::Simulation sim(files);
    while (sim.time() < a.time_s - 1e-9) sim.advance(std::min(0.005, a.time_s - sim.time()));
    if (a.sequence > 0)
      return renderSequence(sim, a.scenario, files.target_config, a.sequence_camera, a.sequence, a.dt_s, a.out);
    if (!a.approach_file.empty()) return renderApproach(sim, a.approach_file, a.out);
    if (a.bench > 0) {
      runBench(sim, a.scenario, a.bench);
      return 0;
    }
    for (int cam = 0; cam < 3; ++cam) {
      const std::string path = a.out + "_" + kCameraNames[cam] + ".png";
      cv::imwrite(path, sim.render(cam));
      std::cout << "wrote " << path << ": " << describe(sim, cam) << "\n";
    }
  } catch (const docking_sim::ConfigError& e) {
    std::cerr << "configuration error: " << e.what() << "\n";
    return 1;
  }
  return 0;
}
