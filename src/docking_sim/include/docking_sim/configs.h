// Loaders for the files the simulator reads: config/sim.yaml, config/target.yaml, config/robot.yaml
// (+ the camera calibrations it names) and config/omni_base.yaml. ROS-free; every loader throws
// ConfigError naming the file and the field.
#pragma once

#include <Eigen/Geometry>
#include <opencv2/core.hpp>

#include <array>
#include <map>
#include <string>
#include <vector>

#include "omni_base/kinematics.h"

namespace docking_sim {

// ---- config/sim.yaml ------------------------------------------------------------------------------

/// What one band of cameras (visible or IR) sees under one lighting scenario.
struct BandLighting {
  double illumination{1.0};   ///< scene brightness factor (1 = the room lights on)
  double noise_sigma{2.0};    ///< Gaussian sensor noise, grey levels
};

/// A bright spot that saturates part of the visible image (sun through a window, a lamp).
struct GlareSpot {
  bool enabled{false};
  double center_u_frac{0.7};  ///< spot centre as a fraction of the image width
  double center_v_frac{0.3};  ///< ... and of the height
  double radius_frac{0.2};    ///< 1/e radius as a fraction of the image width
  double peak{400.0};         ///< added grey levels at the centre (> 255 saturates)
};

struct LightingScenario {
  std::string name;
  BandLighting visible;
  BandLighting ir;
  double led_intensity{1.0};  ///< IR LED drive, 1 = nominal (scales cameras.ir.led_radiance; independent of the room light)
  GlareSpot glare;            ///< visible cameras only
};

/// Per-band optics and sensor: how the raw image departs from an ideal pinhole render. Every field is
/// a key of sim.yaml `cameras.<band>` (dotted: nested block), listed with its range in configs.cpp's
/// kEffectKeys, the one table both sim.yaml and a scenario's `camera_overrides` are read through.
struct CameraEffects {
  double exposure{1.0};        ///< multiplies the scene brightness (with auto-exposure: the target mean)
  double blur_sigma_px{0.6};   ///< residual Gaussian blur (aberrations, sensor), after defocus
  double vignetting{0.25};     ///< relative darkening at the image corners
  /// IR only: the LEDs' radiance at led_intensity 1, relative to the sensor's full scale at exposure 1
  /// (> 1: brighter than anything the exposure is set for; the lens spreads it, the sensor clips it).
  double led_radiance{1.0};
  /// Exposure time at which a lighting scenario's `illumination` holds (auto-exposure off: the time
  /// used); the window of motion blur. The image stamp is the exposure's middle.
  double exposure_time_s{0.02};
  // Thin lens (optics.*): defocus circle of confusion per pixel from the z-buffer.
  double focal_length_mm{3.0};
  double f_number{0.0};         ///< 0: a pinhole (no defocus)
  double focus_distance_m{0.9};
  double pixel_pitch_um{5.6};
  // Auto-exposure and gain (auto_exposure.*).
  bool ae_enabled{false};
  double ae_target_mean{110.0};   ///< mean grey level it drives the image to (times `exposure`)
  double ae_min_exposure_s{0.0005};
  double ae_max_exposure_s{0.0333};
  double ae_max_gain{8.0};        ///< analog gain after the longest exposure; noise scales with it
  // Motion blur (motion_blur.*): sub-frames across the exposure.
  bool motion_blur_enabled{false};
  double motion_blur_max_subframes{16};
  // Specular (specular.*): a Blinn-Phong lobe on glossy surfaces (the target's face print).
  double specular_strength{0.0};
  double specular_shininess{40.0};
};

/// Reads `cameras.<band>`-style keys from `block` into `effects`. partial = false (sim.yaml): every key
/// is required; partial = true (a scenario's camera_overrides): only the keys present are set, and an
/// unknown key is an error. ir_band: whether IR-only keys (led_radiance) are allowed. Throws ConfigError.
class YamlField;
void readCameraEffects(const YamlField& block, bool partial, bool ir_band, CameraEffects* effects);

/// Thin-lens circle of confusion: its diameter in pixels for a point at depth z_m, with the lens
/// focused at focus_distance_m: A f |z - s| / (z (s - f)) / pitch with A = f / N. 0 for a pinhole.
double circleOfConfusionPx(const CameraEffects& e, double z_m);
/// The Gaussian sigma (px) with the second moment of a uniform disc of that diameter: d / 4.
double defocusSigmaPx(const CameraEffects& e, double z_m);

struct ClutterBox {
  std::string name;
  double x_m{0}, y_m{0}, yaw_rad{0};           ///< centre of the footprint on the floor
  double size_x_m{0}, size_y_m{0}, size_z_m{0};
  std::string material;                         ///< wood | cardboard | metal | fabric | plastic | busy | photo
  cv::Vec3b color_bgr{128, 128, 128};
};

struct RoomConfig {
  double x_min_m{-2}, x_max_m{8}, y_min_m{-3.5}, y_max_m{3.5}, height_m{2.6};
  std::vector<ClutterBox> clutter;
};

struct SimSettings {
  double physics_rate_hz{200.0};
  double camera_rate_hz{30.0};
  double encoder_rate_hz{100.0};
  double truth_tf_rate_hz{50.0};
  double real_time_factor{1.0};      ///< <= 0: as fast as possible
  int render_threads{2};             ///< threads rendering the cameras of one instant (1: one after another)
  double stereo_right_rate_hz{0.0};  ///< the right stereo camera's own rate (0: camera_rate_hz)
  double command_timeout_s{0.25};    ///< wheel commands older than this: set-points zero
  Eigen::Vector3d light_direction{0.3, 0.2, -1.0};  ///< direction the key light travels (world)
  double ambient{0.45};              ///< shading floor: fraction of light every surface gets
  CameraEffects visible_effects;
  CameraEffects ir_effects;
  std::map<std::string, LightingScenario> lighting;
  RoomConfig room;
  std::string file;                  ///< where it was read from (for messages)
};

SimSettings loadSimSettings(const std::string& path);

/// One clutter box {name, xy_m, yaw_deg, size_m, material, color_bgr} (sim.yaml room.clutter and a
/// scenario's extra_clutter). Throws ConfigError.
ClutterBox readClutterBox(const YamlField& c);

// ---- config/target.yaml ---------------------------------------------------------------------------

/// target.inner_pattern: a small AprilTag printed near the port so that the visible camera still sees
/// something it can take a pose from at contact (docking_perception's InnerPatternDetector reads it).
struct InnerPatternConfig {
  bool present{false};
  std::string family{"tag36h11"};
  int id{0};
  double size_m{0};                           ///< edge of the tag's black square (apriltag's tagsize)
  Eigen::Vector3d center_m{Eigen::Vector3d::Zero()};  ///< in frame `target`, on the face (x = 0)
};

struct TargetModel {
  std::string frame_id;
  double face_width_m{0}, face_height_m{0};
  std::string texture_path;                  ///< resolved against the file's folder
  std::vector<Eigen::Vector3d> markers_m;    ///< in frame `target` (the port)
  double marker_radius_m{0}, led_radius_m{0}, port_radius_m{0};
  double body_depth_m{0};
  cv::Vec3b body_bgr{150, 150, 155};
  double panel_span_m{0}, panel_height_m{0}, panel_offset_x_m{0};
  cv::Vec3b panel_bgr{110, 40, 20};
  Eigen::Isometry3d robot_T_port{Eigen::Isometry3d::Identity()};  ///< the mount
  InnerPatternConfig inner_pattern;          ///< optional
  std::string file;
};

TargetModel loadTargetModel(const std::string& path);

// ---- config/robot.yaml + config/cameras/*.yaml ----------------------------------------------------

/// The camera_calibration_parsers YAML format, read with yaml-cpp (the core stays ROS-free).
struct CameraCalibration {
  std::string name;
  int width{0}, height{0};
  cv::Matx33d K;
  std::vector<double> D;          ///< plumb_bob: k1 k2 p1 p2 k3
  cv::Matx34d P;
  std::string file;
};

CameraCalibration loadCameraCalibration(const std::string& path);

enum class Band { kVisible, kInfrared };

struct CameraMount {
  std::string key;                 ///< stereo_left | stereo_right | ir
  std::string frame_id;            ///< the camera's tf frame (robot.yaml mount)
  std::string image_frame_id;      ///< frame_id its images carry (the right camera of a stereo pair
                                   ///< uses the left's: stereo_image_proc requires one frame per pair)
  std::string calibration_file;    ///< resolved path
  Eigen::Isometry3d base_T_camera{Eigen::Isometry3d::Identity()};
  CameraCalibration calibration;
  Band band{Band::kVisible};
};

/// The three cameras in a fixed order: kStereoLeft, kStereoRight, kIr.
struct RobotModel {
  static constexpr int kStereoLeft = 0, kStereoRight = 1, kIr = 2;
  std::array<CameraMount, 3> cameras;
  double footprint_radius_m{0.18};
  std::string file;
};

RobotModel loadRobotModel(const std::string& path);

// ---- config/omni_base.yaml ------------------------------------------------------------------------

struct OmniBaseModel {
  omni_base::WheelLayout layout;
  double motor_time_constant_s{0.02};
  double encoder_counts_per_rev{1320};
  std::string file;
};

OmniBaseModel loadOmniBaseModel(const std::string& path);

/// Folder part of a path ("" -> "."), for resolving paths relative to a config file.
std::string folderOf(const std::string& path);
/// `relative` resolved against `folder` unless it is absolute.
std::string resolvePath(const std::string& folder, const std::string& relative);

}  // namespace docking_sim
