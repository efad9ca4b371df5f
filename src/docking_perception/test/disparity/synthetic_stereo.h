// Test and benchmark support (not part of the core library): renders a rectified stereo pair of a
// simple scene with known geometry, and reads the matcher settings of config/stereo_image_proc.yaml,
// so gtests and bench_disparity run the same matcher as the launch file.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include <opencv2/calib3d.hpp>
#include <opencv2/core.hpp>

#include "docking_perception/disparity/window_rectifier.h"
#include "docking_perception/disparity/disparity_detector.h"
#include "docking_perception/disparity/target_track_gate.h"
#include "docking_perception/disparity/tracking_window.h"

namespace docking_perception {
namespace disparity {
namespace testing {

// A textured rectangle facing the cameras (constant depth), in the left rectified optical frame.
struct FrontoParallelRect {
  double x_m = 0.0, y_m = 0.0, z_m = 1.0;  // centre
  double width_m = 0.1, height_m = 0.1;
  double texture_cell_m = 0.02;           // size of the texture's random cells
  std::uint32_t texture_seed = 1;
};

struct SyntheticScene {
  int width = 640, height = 480;
  double focal_px = 550.0, cx_px = 319.5, cy_px = 239.5, baseline_m = 0.10;
  std::vector<FrontoParallelRect> rects;
  double background_z_m = 0.0;      // textured wall at this depth behind everything; 0: none (black)
  double background_cell_m = 0.15;
  double floor_y_m = 0.0;           // textured floor this far below the optical axis; 0: none
  double floor_cell_m = 0.05;
  double noise_sigma_grey = 2.0;    // sensor noise on each image
  std::uint32_t noise_seed = 7;
};

// A textured box standing on the test bed's floor (0.25 m below the cameras), fronto-parallel, its centre
// `x` m to the side at depth `z`.
FrontoParallelRect boxOnTheFloor(double x, double z, double width, double height, std::uint32_t seed);

// A webcam-like camera: 640x480, barrel distortion, a small rectifying rotation (for the rectifier's tests).
PinholeCalibration distortedWebcam();

// Renders the rectified left and right images (CV_8UC1, 2x2 supersampled). The right camera sits
// baseline_m along +x, so a point at depth Z appears f B / Z pixels further left in the right image.
void renderStereoPair(const SyntheticScene& scene, cv::Mat* left, cv::Mat* right);

// stereo_image_proc's disparity parameters (the names of its Disparity.cfg).
struct MatcherSettings {
  int stereo_algorithm = 0;  // 0: StereoBM, 1: StereoSGBM
  int prefilter_size = 9, prefilter_cap = 31, correlation_window_size = 15;
  int min_disparity = 0, disparity_range = 64;
  double uniqueness_ratio = 15.0;
  int texture_threshold = 10, speckle_size = 100, speckle_range = 4;
  bool full_dp = false;
  double p1 = 200.0, p2 = 400.0;
  int disp12_max_diff = 0;
};

// Reads the settings from the YAML file that perception.launch loads into stereo_image_proc's
// disparity nodelet. Throws std::runtime_error naming the file and the field when one is missing.
MatcherSettings loadMatcherSettings(const std::string& path);

// The matcher stereo_image_proc builds from those settings.
cv::Ptr<cv::StereoMatcher> createMatcher(const MatcherSettings& settings);

// Disparity in pixels (CV_32F) as stereo_image_proc publishes it: fixed-point / 16, invalid < min.
cv::Mat computeDisparity(cv::StereoMatcher& matcher, const cv::Mat& left_rect,
                         const cv::Mat& right_rect);

// The highest disparity the matcher searches (its range is rounded down to a multiple of 16).
int maxDisparity(const MatcherSettings& settings);

// The part of the left image where the matcher can produce disparities: the left border is blind
// (no right-image pixels for the largest disparity plus half the correlation window).
cv::Rect matcherValidRegion(const MatcherSettings& settings, cv::Size image_size);

// The disparity detector's and far_stereo_rectify's settings as shipped: the declared defaults with the
// values of `config_dir`'s disparity_detector.yaml and far_stereo.yaml (what the nodes run). Throws
// docking_settings::ConfigError naming a key the declaration does not allow.
DisparityDetectorSettings shippedDetectorSettings(const std::string& config_dir);
FarStereoSettings shippedFarStereoSettings(const std::string& config_dir);
// The rig the detector derives its limits from, as the node reads it: `config_dir`'s robot.yaml and target.yaml,
// and the matcher's window of its stereo_image_proc.yaml.
RigGeometry shippedRig(const std::string& config_dir);

// A camera in ROS camera_calibration's YAML format (config/cameras/*.yaml).
struct CameraCalibration {
  cv::Size size;
  cv::Mat camera_matrix, distortion, rectification, projection;  // CV_64F
};
CameraCalibration loadCameraCalibration(const std::string& path);
// The same camera in the core library's form (WindowRectifier).
PinholeCalibration pinholeOf(const CameraCalibration& calibration);

// What the matcher of `settings` needs around a pixel (far_stereo_rectify reads the same from
// config/stereo_image_proc.yaml).
MatcherReach matcherReachOf(const MatcherSettings& settings);

// A rendered (rectified) pair as the far stage sees it: each image through WindowRectifier (the scene's
// cameras have no distortion), and the stereo geometry.
struct FarStagePair {
  cv::Mat left, right;
  StereoGeometry geometry;
};
FarStagePair farStagePair(const SyntheticScene& scene);

// The target mockup of config/target.yaml seen face-on at `position_m` (the port centre, left
// rectified optical frame), with its body and solar panels behind the face, on a floor 0.25 m below
// the cameras, in front of a wall at `wall_z_m`.
SyntheticScene targetScene(double x_m, double y_m, double z_m, double wall_z_m);

// The rectified stereo geometry the scene was rendered with.
StereoGeometry geometryOf(const SyntheticScene& scene);

// The left rectified camera's projection P of a geometry (what far_stereo_rectify places windows with).
cv::Matx34d projectionOf(const StereoGeometry& geometry);

}  // namespace testing
}  // namespace disparity
}  // namespace docking_perception
