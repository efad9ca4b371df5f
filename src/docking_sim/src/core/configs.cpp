#include "docking_sim/configs.h"

#include <docking_settings/yaml_loader.h>

#include "omni_base/base_settings.h"

#include <cmath>
#include <set>

#include "yaml_field.h"

namespace docking_sim {
namespace {

constexpr double kDegToRad = M_PI / 180.0;

cv::Vec3b readColor(const YamlField& field) {
  const auto c = field.asVector(3);
  for (std::size_t i = 0; i < 3; ++i) {
    if (c[i] < 0 || c[i] > 255) field.at(i).fail("colour components must be within [0, 255]");
  }
  return cv::Vec3b(static_cast<uchar>(c[0]), static_cast<uchar>(c[1]), static_cast<uchar>(c[2]));
}

BandLighting readBand(const YamlField& f) {
  BandLighting b;
  b.illumination = f["illumination"].asDouble(0.0, 10.0);
  b.noise_sigma = f["noise_sigma"].asDouble(0.0, 60.0);
  return b;
}

Eigen::Isometry3d poseFromXyzRpy(const std::vector<double>& xyz, const std::vector<double>& rpy) {
  Eigen::Isometry3d t = Eigen::Isometry3d::Identity();
  t.translation() = Eigen::Vector3d(xyz[0], xyz[1], xyz[2]);
  // Fixed-axis roll, pitch, yaw (the URDF / tf convention): R = Rz(yaw) Ry(pitch) Rx(roll).
  t.linear() = (Eigen::AngleAxisd(rpy[2], Eigen::Vector3d::UnitZ()) *
                Eigen::AngleAxisd(rpy[1], Eigen::Vector3d::UnitY()) *
                Eigen::AngleAxisd(rpy[0], Eigen::Vector3d::UnitX()))
                   .toRotationMatrix();
  return t;
}

/// Every key of a `cameras.<band>` block: dotted path, range, where it goes. One home for each
/// camera setting's name and range (defaults and documentation: config/sim.yaml).
struct EffectKey {
  const char* path;
  double min, max;
  double CameraEffects::*number;  ///< null for a bool key
  bool CameraEffects::*flag;      ///< null for a number key
  bool ir_only;
};

const EffectKey kEffectKeys[] = {
    {"exposure", 0.0, 20.0, &CameraEffects::exposure, nullptr, false},
    {"blur_sigma_px", 0.0, 10.0, &CameraEffects::blur_sigma_px, nullptr, false},
    {"vignetting", 0.0, 0.95, &CameraEffects::vignetting, nullptr, false},
    {"led_radiance", 0.0, 1000.0, &CameraEffects::led_radiance, nullptr, true},
    {"exposure_time_s", 1e-5, 1.0, &CameraEffects::exposure_time_s, nullptr, false},
    {"optics.focal_length_mm", 0.5, 100.0, &CameraEffects::focal_length_mm, nullptr, false},
    {"optics.f_number", 0.0, 64.0, &CameraEffects::f_number, nullptr, false},
    {"optics.focus_distance_m", 0.01, 1e6, &CameraEffects::focus_distance_m, nullptr, false},
    {"optics.pixel_pitch_um", 0.5, 50.0, &CameraEffects::pixel_pitch_um, nullptr, false},
    {"auto_exposure.enabled", 0, 0, nullptr, &CameraEffects::ae_enabled, false},
    {"auto_exposure.target_mean", 1.0, 254.0, &CameraEffects::ae_target_mean, nullptr, false},
    {"auto_exposure.min_exposure_s", 1e-6, 1.0, &CameraEffects::ae_min_exposure_s, nullptr, false},
    {"auto_exposure.max_exposure_s", 1e-6, 1.0, &CameraEffects::ae_max_exposure_s, nullptr, false},
    {"auto_exposure.max_gain", 1.0, 64.0, &CameraEffects::ae_max_gain, nullptr, false},
    {"motion_blur.enabled", 0, 0, nullptr, &CameraEffects::motion_blur_enabled, false},
    {"motion_blur.max_subframes", 1.0, 64.0, &CameraEffects::motion_blur_max_subframes, nullptr, false},
    {"specular.strength", 0.0, 100.0, &CameraEffects::specular_strength, nullptr, false},
    {"specular.shininess", 1.0, 1e6, &CameraEffects::specular_shininess, nullptr, false},
};

// (YamlField is never re-assigned: YAML::Node's assignment writes into the tree it refers to.)

/// The field at a dotted path below `block` (at most one dot: a key or block.key).
YamlField fieldAt(const YamlField& block, const std::string& path) {
  const auto dot = path.find('.');
  return dot == std::string::npos ? block[path] : block[path.substr(0, dot)][path.substr(dot + 1)];
}

/// Whether a dotted path exists below `block`.
bool hasPath(const YamlField& block, const std::string& path) {
  const auto dot = path.find('.');
  if (dot == std::string::npos) return block.has(path);
  const std::string head = path.substr(0, dot);
  return block.has(head) && block[head].isMap() && block[head].has(path.substr(dot + 1));
}

}  // namespace

void readCameraEffects(const YamlField& block, bool partial, bool ir_band, CameraEffects* effects) {
  if (partial) {
    // Reject what the table does not know (a typo would silently change nothing).
    if (!block.isMap()) block.fail("must be a map of camera settings");
    for (const auto& key : block.keys()) {
      const YamlField sub = block[key];
      const std::vector<std::string> leaves = sub.isMap() ? sub.keys() : std::vector<std::string>{""};
      for (const auto& leaf : leaves) {
        const std::string path = leaf.empty() ? key : key + "." + leaf;
        bool known = false;
        for (const auto& k : kEffectKeys) known = known || path == k.path;
        if (!known) (leaf.empty() ? sub : sub[leaf]).fail("unknown camera setting '" + path + "'");
      }
    }
  }
  for (const auto& k : kEffectKeys) {
    if (k.ir_only && !ir_band) {
      if (hasPath(block, k.path)) fieldAt(block, k.path).fail("an IR camera setting only");
      continue;
    }
    if (partial && !hasPath(block, k.path)) continue;
    const YamlField f = fieldAt(block, k.path);
    if (k.flag) {
      effects->*k.flag = f.asBool();
    } else {
      effects->*k.number = f.asDouble(k.min, k.max);
    }
  }
  if (effects->ae_min_exposure_s > effects->ae_max_exposure_s) {
    block.fail("auto_exposure.min_exposure_s must not exceed max_exposure_s");
  }
  if (effects->f_number > 0.0 && effects->focus_distance_m * 1e3 <= effects->focal_length_mm) {
    block.fail("optics.focus_distance_m must lie beyond the focal length");
  }
  effects->motion_blur_max_subframes = std::round(effects->motion_blur_max_subframes);
}

double circleOfConfusionPx(const CameraEffects& e, double z_m) {
  if (!(e.f_number > 0.0) || !(z_m > 0.0)) return 0.0;
  const double f = e.focal_length_mm * 1e-3, s = e.focus_distance_m, aperture = f / e.f_number;
  const double diameter_m = aperture * f * std::abs(z_m - s) / (z_m * (s - f));
  return diameter_m / (e.pixel_pitch_um * 1e-6);
}

double defocusSigmaPx(const CameraEffects& e, double z_m) { return 0.25 * circleOfConfusionPx(e, z_m); }

ClutterBox readClutterBox(const YamlField& c) {
  static const std::set<std::string> kMaterials{"wood", "cardboard", "metal", "fabric", "plastic", "busy", "photo"};
  ClutterBox box;
  box.name = c["name"].asString();
  const auto xy = c["xy_m"].asVector(2);
  box.x_m = xy[0];
  box.y_m = xy[1];
  box.yaw_rad = c["yaw_deg"].asDouble(-360.0, 360.0) * kDegToRad;
  const auto size = c["size_m"].asVector(3);
  for (std::size_t k = 0; k < 3; ++k) {
    if (!(size[k] > 0.0)) c["size_m"].at(k).fail("must be > 0");
  }
  box.size_x_m = size[0];
  box.size_y_m = size[1];
  box.size_z_m = size[2];
  box.material = c["material"].asString();
  if (!kMaterials.count(box.material)) {
    c["material"].fail("unknown material '" + box.material +
                       "' (wood, cardboard, metal, fabric, plastic, busy, photo)");
  }
  box.color_bgr = readColor(c["color_bgr"]);
  return box;
}

std::string folderOf(const std::string& path) {
  const auto slash = path.find_last_of('/');
  if (slash == std::string::npos) return ".";
  if (slash == 0) return "/";
  return path.substr(0, slash);
}

std::string resolvePath(const std::string& folder, const std::string& relative) {
  if (!relative.empty() && relative[0] == '/') return relative;
  return folder + "/" + relative;
}

namespace {

// sim.yaml's sections, read in file order (the first bad value is the one reported).

void readSimRates(const YamlField& sim, SimSettings* s) {
  s->physics_rate_hz = sim["physics_rate_hz"].asDouble(10.0, 5000.0);
  s->camera_rate_hz = sim["camera_rate_hz"].asDouble(0.1, 200.0);
  s->encoder_rate_hz = sim["encoder_rate_hz"].asDouble(1.0, 1000.0);
  s->truth_tf_rate_hz = sim["truth_tf_rate_hz"].asDouble(1.0, 1000.0);
  s->real_time_factor = sim["real_time_factor"].asDouble(0.0, 100.0);
  s->render_threads = static_cast<int>(sim["render_threads"].asInteger(1, 3));
  s->stereo_right_rate_hz = sim["stereo_right_rate_hz"].asDouble(0.0, 200.0);
  s->command_timeout_s = sim["command_timeout_s"].asDouble(0.01, 10.0);
}

void readShading(const YamlField& shading, SimSettings* s) {
  const auto dir = shading["light_direction"].asVector(3);
  s->light_direction = Eigen::Vector3d(dir[0], dir[1], dir[2]);
  if (s->light_direction.norm() < 1e-6) shading["light_direction"].fail("must not be the zero vector");
  s->light_direction.normalize();
  s->ambient = shading["ambient"].asDouble(0.0, 1.0);
}

LightingScenario readLightingScenario(const std::string& name, const YamlField& l) {
  LightingScenario ls;
  ls.name = name;
  ls.visible = readBand(l["visible"]);
  ls.ir = readBand(l["ir"]);
  ls.led_intensity = l["led_intensity"].asDouble(0.0, 10.0);
  if (l.has("glare")) {
    const YamlField g = l["glare"];
    const auto center = g["center"].asVector(2);
    ls.glare.enabled = true;
    ls.glare.center_u_frac = center[0];
    ls.glare.center_v_frac = center[1];
    ls.glare.radius_frac = g["radius"].asDouble(0.01, 2.0);
    ls.glare.peak = g["peak"].asDouble(0.0, 5000.0);
  }
  return ls;
}

RoomConfig readRoom(const YamlField& room) {
  RoomConfig r;
  const auto xr = room["x_m"].asVector(2);
  const auto yr = room["y_m"].asVector(2);
  if (!(xr[1] - xr[0] > 1.0)) room["x_m"].fail("needs [min, max] with max - min > 1 m");
  if (!(yr[1] - yr[0] > 1.0)) room["y_m"].fail("needs [min, max] with max - min > 1 m");
  r.x_min_m = xr[0];
  r.x_max_m = xr[1];
  r.y_min_m = yr[0];
  r.y_max_m = yr[1];
  r.height_m = room["height_m"].asDouble(1.0, 20.0);
  if (room.has("clutter")) {
    const YamlField clutter = room["clutter"];
    for (std::size_t i = 0; i < clutter.size(); ++i) r.clutter.push_back(readClutterBox(clutter.at(i)));
  }
  return r;
}

}  // namespace

SimSettings loadSimSettings(const std::string& path) {
  const YamlField root = YamlField::open(path);
  SimSettings s;
  s.file = path;
  readSimRates(root["sim"], &s);
  readShading(root["shading"], &s);
  readCameraEffects(root["cameras"]["visible"], false, false, &s.visible_effects);
  readCameraEffects(root["cameras"]["ir"], false, true, &s.ir_effects);
  const YamlField lighting = root["lighting"];
  for (const auto& name : lighting.keys()) s.lighting[name] = readLightingScenario(name, lighting[name]);
  if (s.lighting.empty()) lighting.fail("needs at least one lighting scenario");
  s.room = readRoom(root["room"]);
  return s;
}

namespace {

// target.inner_pattern (optional): the tag must lie on the face, its white ring included.
InnerPatternConfig readInnerPattern(const YamlField& f, const TargetModel& m) {
  InnerPatternConfig p;
  p.present = true;
  const std::string type = f["type"].asString();
  if (type != "apriltag") f["type"].fail("only 'apriltag' is supported, got '" + type + "'");
  p.family = f["family"].asString();
  if (p.family != "tag36h11") f["family"].fail("only tag36h11 is supported, got '" + p.family + "'");
  p.id = static_cast<int>(f["id"].asInteger(0, 586));
  p.size_m = f["size_m"].asDouble(0.005, 1.0);
  const auto c = f["center_m"].asVector(3);
  p.center_m = Eigen::Vector3d(c[0], c[1], c[2]);
  if (std::abs(c[0]) > 1e-9) f["center_m"].fail("must lie on the face (x = 0)");
  const double half_print = 0.5 * p.size_m * 10.0 / 8.0;  // tag36h11: 8 black cells of 10 with the ring
  if (std::abs(c[1]) + half_print > m.face_width_m / 2 || std::abs(c[2]) + half_print > m.face_height_m / 2) {
    f["center_m"].fail("the tag (with its white ring) does not fit on the face");
  }
  return p;
}

}  // namespace

TargetModel loadTargetModel(const std::string& path) {
  const YamlField root = YamlField::open(path);
  const YamlField t = root["target"];
  TargetModel m;
  m.file = path;
  m.frame_id = t["frame_id"].asString();
  m.face_width_m = t["face"]["width_m"].asDouble(0.01, 5.0);
  m.face_height_m = t["face"]["height_m"].asDouble(0.01, 5.0);
  m.texture_path = resolvePath(folderOf(path), t["face"]["texture"].asString());
  const YamlField markers = t["markers_m"];
  if (markers.size() != 5) markers.fail("expected 5 markers, got " + std::to_string(markers.size()));
  for (std::size_t i = 0; i < markers.size(); ++i) {
    const auto p = markers.at(i).asVector(3);
    if (std::abs(p[1]) > m.face_width_m / 2 || std::abs(p[2]) > m.face_height_m / 2) {
      markers.at(i).fail("marker lies outside the face");
    }
    m.markers_m.emplace_back(p[0], p[1], p[2]);
  }
  m.marker_radius_m = t["marker_radius_m"].asDouble(0.0005, 0.5);
  m.led_radius_m = t["led_radius_m"].asDouble(0.0005, 0.5);
  m.port_radius_m = t["port_radius_m"].asDouble(0.001, 1.0);
  m.body_depth_m = t["body"]["depth_m"].asDouble(0.01, 5.0);
  m.body_bgr = readColor(t["body"]["color_bgr"]);
  m.panel_span_m = t["solar_panels"]["span_m"].asDouble(0.0, 5.0);
  m.panel_height_m = t["solar_panels"]["height_m"].asDouble(0.0, 5.0);
  m.panel_offset_x_m = t["solar_panels"]["offset_x_m"].asDouble(-5.0, 0.0);
  m.panel_bgr = readColor(t["solar_panels"]["color_bgr"]);
  const auto mount_xyz = t["mount"]["xyz_m"].asVector(3);
  const double mount_yaw = t["mount"]["yaw_rad"].asDouble(-2 * M_PI, 2 * M_PI);
  m.robot_T_port = poseFromXyzRpy(mount_xyz, {0.0, 0.0, mount_yaw});
  if (mount_xyz[2] - m.face_height_m / 2 < 0.0) t["mount"]["xyz_m"].fail("puts the face below the floor");
  if (t.has("inner_pattern")) m.inner_pattern = readInnerPattern(t["inner_pattern"], m);
  return m;
}

CameraCalibration loadCameraCalibration(const std::string& path) {
  const YamlField root = YamlField::open(path);
  CameraCalibration c;
  c.file = path;
  c.name = root["camera_name"].asString();
  c.width = static_cast<int>(root["image_width"].asInteger(16, 10000));
  c.height = static_cast<int>(root["image_height"].asInteger(16, 10000));
  const auto k = root["camera_matrix"]["data"].asVector(9);
  c.K = cv::Matx33d(k.data());
  if (!(c.K(0, 0) > 0 && c.K(1, 1) > 0)) root["camera_matrix"]["data"].fail("focal lengths must be > 0");
  const std::string model = root["distortion_model"].asString();
  if (model != "plumb_bob") root["distortion_model"].fail("only plumb_bob is supported, got '" + model + "'");
  c.D = root["distortion_coefficients"]["data"].asVector(5);
  const auto p = root["projection_matrix"]["data"].asVector(12);
  c.P = cv::Matx34d(p.data());
  return c;
}

RobotModel loadRobotModel(const std::string& path) {
  const YamlField root = YamlField::open(path);
  const YamlField chaser = root["chaser"];
  RobotModel r;
  r.file = path;
  r.footprint_radius_m = chaser["footprint_radius_m"].asDouble(0.01, 2.0);
  const char* keys[3] = {"stereo_left", "stereo_right", "ir"};
  for (int i = 0; i < 3; ++i) {
    const YamlField cam = chaser["cameras"][keys[i]];
    CameraMount& m = r.cameras[static_cast<std::size_t>(i)];
    m.key = keys[i];
    m.band = (i == RobotModel::kIr) ? Band::kInfrared : Band::kVisible;
    m.frame_id = cam["frame_id"].asString();
    m.image_frame_id = cam.has("image_frame_id") ? cam["image_frame_id"].asString() : m.frame_id;
    m.calibration_file = resolvePath(folderOf(path), cam["calibration"].asString());
    m.base_T_camera = poseFromXyzRpy(cam["xyz_m"].asVector(3), cam["rpy_rad"].asVector(3));
    try {
      m.calibration = loadCameraCalibration(m.calibration_file);
    } catch (const ConfigError& e) {
      // Name both: the robot file's field that points there, and the calibration's own problem.
      throw ConfigError(path, cam["calibration"].name(), e.what());
    }
  }
  return r;
}

OmniBaseModel loadOmniBaseModel(const std::string& path) {
  // The base as omni_base_node reads it (settings/omni_base.yaml): the same checks, one copy.
  omni_base::OmniBaseSettings settings;
  try {
    settings = docking_settings::shippedSettings<omni_base::OmniBaseSettings>(path);
    omni_base::validate(settings);
  } catch (const docking_settings::ConfigError& e) {
    throw std::runtime_error(path + ": " + e.key() + ": " + e.detail());
  }
  OmniBaseModel m;
  m.file = path;
  m.layout = omni_base::wheelLayout(settings.wheels);
  if (m.layout.drive_angles_rad.size() < 3) throw std::runtime_error(path + ": wheels/names: needs at least 3 wheels");
  m.encoder_counts_per_rev = settings.wheels.encoder_counts_per_rev;
  m.motor_time_constant_s = settings.motor.time_constant_s;
  return m;
}

}  // namespace docking_sim
