#include "synthetic_stereo.h"

#include <docking_settings/yaml_loader.h>

#include <algorithm>
#include <cmath>
#include <iterator>
#include <sstream>
#include <fstream>
#include <map>
#include <limits>
#include <random>
#include <stdexcept>

namespace docking_perception {
namespace disparity {
namespace testing {
namespace {

// Deterministic value in [0, 1) for an integer cell of a texture.
double cellValue(long ix, long iy, std::uint32_t seed) {
  std::uint64_t h = static_cast<std::uint64_t>(ix) * 0x9E3779B97F4A7C15ull ^
                    static_cast<std::uint64_t>(iy) * 0xC2B2AE3D27D4EB4Full ^
                    (static_cast<std::uint64_t>(seed) << 32);
  h ^= h >> 33;
  h *= 0xFF51AFD7ED558CCDull;
  h ^= h >> 33;
  h *= 0xC4CEB9FE1A85EC53ull;
  h ^= h >> 33;
  return static_cast<double>(h >> 11) / static_cast<double>(1ull << 53);
}

// Smooth random texture (bilinear value noise) on plane coordinates (a, b), grey 30..230.
double texture(double a, double b, double cell, std::uint32_t seed) {
  const double fa = a / cell, fb = b / cell;
  const long ia = static_cast<long>(std::floor(fa)), ib = static_cast<long>(std::floor(fb));
  const double ta = fa - ia, tb = fb - ib;
  const double v00 = cellValue(ia, ib, seed), v10 = cellValue(ia + 1, ib, seed);
  const double v01 = cellValue(ia, ib + 1, seed), v11 = cellValue(ia + 1, ib + 1, seed);
  const double value = (1 - ta) * (1 - tb) * v00 + ta * (1 - tb) * v10 + (1 - ta) * tb * v01 +
                       ta * tb * v11;
  return 30.0 + 200.0 * value;
}

// Grey value seen along the ray from (camera_x, 0, 0) through rectified pixel (u, v).
double shade(const SyntheticScene& scene, double camera_x, double u, double v) {
  const double ray_x = (u - scene.cx_px) / scene.focal_px;
  const double ray_y = (v - scene.cy_px) / scene.focal_px;
  double nearest_z = std::numeric_limits<double>::infinity();
  double grey = 0.0;
  for (const auto& rect : scene.rects) {
    const double x = camera_x + rect.z_m * ray_x, y = rect.z_m * ray_y;
    if (rect.z_m < nearest_z && std::abs(x - rect.x_m) <= rect.width_m / 2 &&
        std::abs(y - rect.y_m) <= rect.height_m / 2) {
      nearest_z = rect.z_m;
      grey = texture(x, y, rect.texture_cell_m, rect.texture_seed);
    }
  }
  if (scene.floor_y_m > 0.0 && ray_y > 0.0) {
    const double z = scene.floor_y_m / ray_y;
    if (z < nearest_z) {
      nearest_z = z;
      grey = texture(camera_x + z * ray_x, z, scene.floor_cell_m, 991);
    }
  }
  if (scene.background_z_m > 0.0 && scene.background_z_m < nearest_z) {
    const double z = scene.background_z_m;
    grey = texture(camera_x + z * ray_x, z * ray_y, scene.background_cell_m, 577);
  }
  return grey;
}

cv::Mat renderView(const SyntheticScene& scene, double camera_x, std::mt19937* rng) {
  cv::Mat image(scene.height, scene.width, CV_8UC1);
  std::normal_distribution<double> noise(0.0, scene.noise_sigma_grey);
  for (int v = 0; v < scene.height; ++v) {
    auto* row = image.ptr<std::uint8_t>(v);
    for (int u = 0; u < scene.width; ++u) {
      double sum = 0.0;
      for (double dv : {-0.25, 0.25}) {
        for (double du : {-0.25, 0.25}) sum += shade(scene, camera_x, u + du, v + dv);
      }
      const double value = sum / 4.0 + (scene.noise_sigma_grey > 0 ? noise(*rng) : 0.0);
      row[u] = cv::saturate_cast<std::uint8_t>(value);
    }
  }
  return image;
}

// Flat "key: value" YAML as rosparam loads it (OpenCV's FileStorage insists on its own header).
std::map<std::string, std::string> readFlatYaml(const std::string& path) {
  std::ifstream file(path);
  if (!file) throw std::runtime_error("cannot read matcher settings file " + path);
  std::map<std::string, std::string> fields;
  std::string line;
  while (std::getline(file, line)) {
    line = line.substr(0, line.find('#'));
    const auto colon = line.find(':');
    if (colon == std::string::npos) continue;
    auto trim = [](std::string text) {
      const auto first = text.find_first_not_of(" \t\r");
      const auto last = text.find_last_not_of(" \t\r");
      return first == std::string::npos ? std::string() : text.substr(first, last - first + 1);
    };
    fields[trim(line.substr(0, colon))] = trim(line.substr(colon + 1));
  }
  return fields;
}

double readNumber(const std::map<std::string, std::string>& fields, const std::string& path,
                  const std::string& name) {
  const auto it = fields.find(name);
  if (it == fields.end()) throw std::runtime_error(path + ": missing field '" + name + "'");
  if (it->second == "true") return 1.0;
  if (it->second == "false") return 0.0;
  try {
    std::size_t used = 0;
    const double value = std::stod(it->second, &used);
    if (used != it->second.size()) throw std::invalid_argument(it->second);
    return value;
  } catch (const std::exception&) {
    throw std::runtime_error(path + ": field '" + name + "' is not a number: '" + it->second + "'");
  }
}

}  // namespace

FrontoParallelRect boxOnTheFloor(double x, double z, double width, double height, std::uint32_t seed) {
  FrontoParallelRect box;
  box.x_m = x;
  box.z_m = z;
  box.width_m = width;
  box.height_m = height;
  box.y_m = 0.25 - height / 2.0;
  box.texture_cell_m = 0.04;
  box.texture_seed = seed;
  return box;
}

PinholeCalibration distortedWebcam() {
  PinholeCalibration c;
  c.size = cv::Size(640, 480);
  c.camera_matrix = cv::Matx33d(560.0, 0.0, 322.0, 0.0, 558.0, 236.0, 0.0, 0.0, 1.0);
  c.distortion = {-0.12, 0.05, 0.001, -0.0005, 0.0};
  cv::Mat rotation;
  cv::Rodrigues(cv::Vec3d(0.004, -0.01, 0.002), rotation);
  c.rectification = cv::Matx33d(rotation);
  c.projection = cv::Matx34d(550.0, 0.0, 318.0, 0.0, 0.0, 550.0, 241.0, 0.0, 0.0, 0.0, 1.0, 0.0);
  return c;
}

void renderStereoPair(const SyntheticScene& scene, cv::Mat* left, cv::Mat* right) {
  std::mt19937 rng(scene.noise_seed);
  *left = renderView(scene, 0.0, &rng);
  *right = renderView(scene, scene.baseline_m, &rng);
}

MatcherSettings loadMatcherSettings(const std::string& path) {
  const auto fields = readFlatYaml(path);
  auto integer = [&](const char* name) { return static_cast<int>(readNumber(fields, path, name)); };
  MatcherSettings s;
  s.stereo_algorithm = integer("stereo_algorithm");
  s.prefilter_size = integer("prefilter_size");
  s.prefilter_cap = integer("prefilter_cap");
  s.correlation_window_size = integer("correlation_window_size");
  s.min_disparity = integer("min_disparity");
  s.disparity_range = integer("disparity_range");
  s.uniqueness_ratio = readNumber(fields, path, "uniqueness_ratio");
  s.texture_threshold = integer("texture_threshold");
  s.speckle_size = integer("speckle_size");
  s.speckle_range = integer("speckle_range");
  s.full_dp = integer("fullDP") != 0;
  s.p1 = readNumber(fields, path, "P1");
  s.p2 = readNumber(fields, path, "P2");
  s.disp12_max_diff = integer("disp12MaxDiff");
  return s;
}

DisparityDetectorSettings shippedDetectorSettings(const std::string& config_dir) {
  return docking_settings::shippedSettings<DisparityDetectorSettings>(config_dir + "/disparity_detector.yaml");
}

RigGeometry shippedRig(const std::string& config_dir) {
  return loadRigGeometry(config_dir + "/robot.yaml", config_dir + "/target.yaml",
                         loadMatcherSettings(config_dir + "/stereo_image_proc.yaml").correlation_window_size);
}

FarStereoSettings shippedFarStereoSettings(const std::string& config_dir) {
  return docking_settings::shippedSettings<FarStereoSettings>(config_dir + "/far_stereo.yaml");
}

CameraCalibration loadCameraCalibration(const std::string& path) {
  std::ifstream file(path);
  if (!file) throw std::runtime_error("cannot read camera calibration " + path);
  const std::string text((std::istreambuf_iterator<char>(file)), std::istreambuf_iterator<char>());
  auto scalar = [&](const std::string& key) {
    const auto at = text.find(key + ":");
    if (at == std::string::npos) throw std::runtime_error(path + ": missing field '" + key + "'");
    return std::stoi(text.substr(at + key.size() + 1));
  };
  // The numbers of `data: [...]` in the block that starts with `key:`.
  auto matrix = [&](const std::string& key, int rows, int cols) {
    const auto at = text.find(key + ":");
    const auto open = at == std::string::npos ? at : text.find('[', text.find("data:", at));
    const auto close = open == std::string::npos ? open : text.find(']', open);
    if (close == std::string::npos) {
      throw std::runtime_error(path + ": missing field '" + key + ".data'");
    }
    std::string numbers = text.substr(open + 1, close - open - 1);
    std::replace(numbers.begin(), numbers.end(), ',', ' ');
    std::istringstream stream(numbers);
    cv::Mat values(rows, cols, CV_64F);
    for (int i = 0; i < rows * cols; ++i) {
      if (!(stream >> values.at<double>(i / cols, i % cols))) {
        throw std::runtime_error(path + ": field '" + key + ".data' needs " +
                                 std::to_string(rows * cols) + " numbers");
      }
    }
    return values;
  };
  CameraCalibration calibration;
  calibration.size = cv::Size(scalar("image_width"), scalar("image_height"));
  calibration.camera_matrix = matrix("camera_matrix", 3, 3);
  calibration.distortion = matrix("distortion_coefficients", 1, 5);
  calibration.rectification = matrix("rectification_matrix", 3, 3);
  calibration.projection = matrix("projection_matrix", 3, 4);
  return calibration;
}

SyntheticScene targetScene(double x_m, double y_m, double z_m, double wall_z_m) {
  // Sizes of config/target.yaml: face 0.30 x 0.24, box 0.30 deep, panels 0.30 x 0.16 on each side
  // at mid depth. The target robot's body below the face is left out.
  SyntheticScene scene;
  FrontoParallelRect face;
  face.x_m = x_m;
  face.y_m = y_m;
  face.z_m = z_m;
  face.width_m = 0.30;
  face.height_m = 0.24;
  face.texture_cell_m = 0.015;
  face.texture_seed = 11;
  scene.rects.push_back(face);
  for (double side : {-1.0, 1.0}) {
    FrontoParallelRect panel;
    panel.x_m = x_m + side * (0.15 + 0.15);
    panel.y_m = y_m;
    panel.z_m = z_m + 0.15;
    panel.width_m = 0.30;
    panel.height_m = 0.16;
    panel.texture_cell_m = 0.03;
    panel.texture_seed = side > 0 ? 12 : 13;
    scene.rects.push_back(panel);
  }
  scene.background_z_m = wall_z_m;
  scene.floor_y_m = 0.25;
  return scene;
}

cv::Ptr<cv::StereoMatcher> createMatcher(const MatcherSettings& s) {
  // The same mapping as stereo_image_proc's configCb: odd windows, a range in multiples of 16.
  const int window = s.correlation_window_size | 1;
  const int range = (s.disparity_range / 16) * 16;
  if (s.stereo_algorithm == 0) {
    auto bm = cv::StereoBM::create(range, window);
    bm->setPreFilterSize(s.prefilter_size | 1);
    bm->setPreFilterCap(s.prefilter_cap);
    bm->setMinDisparity(s.min_disparity);
    bm->setUniquenessRatio(static_cast<int>(s.uniqueness_ratio));
    bm->setTextureThreshold(s.texture_threshold);
    bm->setSpeckleWindowSize(s.speckle_size);
    bm->setSpeckleRange(s.speckle_range);
    return bm;
  }
  auto sgbm = cv::StereoSGBM::create(s.min_disparity, range, window, static_cast<int>(s.p1),
                                     static_cast<int>(s.p2), s.disp12_max_diff, s.prefilter_cap,
                                     static_cast<int>(s.uniqueness_ratio), s.speckle_size,
                                     s.speckle_range,
                                     s.full_dp ? cv::StereoSGBM::MODE_HH : cv::StereoSGBM::MODE_SGBM);
  return sgbm;
}

cv::Mat computeDisparity(cv::StereoMatcher& matcher, const cv::Mat& left_rect,
                         const cv::Mat& right_rect) {
  cv::Mat fixed_point, disparity;
  matcher.compute(left_rect, right_rect, fixed_point);
  fixed_point.convertTo(disparity, CV_32F, 1.0 / 16.0);
  return disparity;
}

int maxDisparity(const MatcherSettings& settings) {
  return settings.min_disparity + (settings.disparity_range / 16) * 16 - 1;
}

cv::Rect matcherValidRegion(const MatcherSettings& settings, cv::Size image_size) {
  const int blind = maxDisparity(settings) + 1 + settings.correlation_window_size / 2;
  return cv::Rect(blind, 0, image_size.width - blind, image_size.height);
}

StereoGeometry geometryOf(const SyntheticScene& scene) {
  StereoGeometry geometry;
  geometry.focal_px = scene.focal_px;
  geometry.cx_px = scene.cx_px;
  geometry.cy_px = scene.cy_px;
  geometry.baseline_m = scene.baseline_m;
  return geometry;
}

cv::Matx34d projectionOf(const StereoGeometry& g) {
  return cv::Matx34d(g.focal_px, 0.0, g.cx_px, 0.0, 0.0, g.focal_px, g.cy_px, 0.0, 0.0, 0.0, 1.0, 0.0);
}

PinholeCalibration pinholeOf(const CameraCalibration& calibration) {
  PinholeCalibration out;
  out.size = calibration.size;
  out.camera_matrix = cv::Matx33d(calibration.camera_matrix);
  out.rectification = cv::Matx33d(calibration.rectification);
  out.projection = cv::Matx34d(calibration.projection);
  const cv::Mat d = calibration.distortion.reshape(1, 1);
  out.distortion.assign(d.ptr<double>(), d.ptr<double>() + d.total());
  return out;
}

MatcherReach matcherReachOf(const MatcherSettings& settings) {
  MatcherReach reach;
  reach.min_disparity = settings.min_disparity;
  reach.disparity_range = settings.disparity_range;
  reach.correlation_window_px = settings.correlation_window_size;
  return reach;
}

FarStagePair farStagePair(const SyntheticScene& scene) {
  cv::Mat left_full, right_full;
  renderStereoPair(scene, &left_full, &right_full);
  PinholeCalibration camera;
  camera.size = cv::Size(scene.width, scene.height);
  camera.camera_matrix = cv::Matx33d(scene.focal_px, 0.0, scene.cx_px, 0.0, scene.focal_px, scene.cy_px, 0.0, 0.0, 1.0);
  camera.rectification = cv::Matx33d::eye();
  camera.projection = cv::Matx34d(scene.focal_px, 0.0, scene.cx_px, 0.0, 0.0, scene.focal_px, scene.cy_px, 0.0,
                                  0.0, 0.0, 1.0, 0.0);
  PinholeCalibration right_camera = camera;
  right_camera.projection(0, 3) = -scene.focal_px * scene.baseline_m;
  FarStagePair pair;
  WindowRectifier(camera).rectify(left_full, &pair.left);
  WindowRectifier(right_camera).rectify(right_full, &pair.right);
  pair.geometry = geometryOf(scene);
  return pair;
}

}  // namespace testing
}  // namespace disparity
}  // namespace docking_perception
