// The realistic camera: thin-lens depth of field, motion blur from the motion during the exposure,
// auto-exposure with gain, specular highlights on the glossy face, the cluttered room variant, and
// the scenario's camera_overrides (parsed, applied, bad values named).
#include <gtest/gtest.h>

#include <opencv2/imgproc.hpp>

#include <algorithm>
#include <cmath>
#include <filesystem>

#include "docking_sim/config_error.h"
#include "docking_sim/renderer.h"
#include "docking_sim/scenario.h"
#include "docking_sim/simulation.h"
#include "test_helpers.h"

using docking_sim::RobotModel;
using docking_sim_test::files;
using docking_sim_test::scenarioText;
using docking_sim_test::writeTempFile;

namespace {

docking_sim::CameraCalibration pinhole(double f) {
  docking_sim::CameraCalibration cal;
  cal.width = 640;
  cal.height = 480;
  cal.K = cv::Matx33d(f, 0, 319.5, 0, f, 239.5, 0, 0, 1);
  cal.D = {0, 0, 0, 0, 0};
  return cal;
}

/// Every effect off: no blur, vignetting, auto-exposure, motion blur, defocus or specular.
docking_sim::CameraEffects plainEffects() {
  docking_sim::CameraEffects e;
  e.blur_sigma_px = 0;
  e.vignetting = 0;
  e.f_number = 0;
  e.ae_enabled = false;
  e.motion_blur_enabled = false;
  e.specular_strength = 0;
  return e;
}

docking_sim::LightingScenario quiet() {
  docking_sim::LightingScenario l;
  l.visible.noise_sigma = 0;
  l.ir.noise_sigma = 0;
  return l;
}

docking_sim::RenderOptions noDistortion() {
  docking_sim::RenderOptions o;
  o.distortion = false;
  return o;
}

/// A fronto-parallel rectangle at depth z (camera = world frame), x in [x0, x1], y in [y0, y1].
docking_sim::Surface card(double x0, double x1, double y0, double y1, double z, uchar grey) {
  docking_sim::Surface s;
  s.origin = Eigen::Vector3d(x0, y0, z);
  s.edge_u = Eigen::Vector3d(x1 - x0, 0, 0);
  s.edge_v = Eigen::Vector3d(0, y1 - y0, 0);
  s.color = cv::Vec3b(grey, grey, grey);
  return s;
}

/// Standard deviation (px) of the line spread along a row: the profile's differences as a density.
double edgeSpreadAlongRow(const cv::Mat& gray, int row, int x_from, int x_to) {
  double sum = 0, sum_x = 0, sum_xx = 0;
  for (int x = x_from; x < x_to; ++x) {
    const double d = std::abs(static_cast<double>(gray.at<uchar>(row, x + 1)) - gray.at<uchar>(row, x));
    sum += d;
    sum_x += d * (x + 0.5);
    sum_xx += d * (x + 0.5) * (x + 0.5);
  }
  const double mean = sum_x / sum;
  return std::sqrt(std::max(0.0, sum_xx / sum - mean * mean));
}

double edgeSpreadAlongColumn(const cv::Mat& gray, int col, int y_from, int y_to) {
  cv::Mat t;
  cv::transpose(gray, t);
  return edgeSpreadAlongRow(t, col, y_from, y_to);
}

cv::Mat toGray(const cv::Mat& image) {
  cv::Mat g;
  if (image.channels() == 3) {
    cv::cvtColor(image, g, cv::COLOR_BGR2GRAY);
  } else {
    g = image.clone();
  }
  return g;
}

std::string scenarioWith(const std::string& extra, double target_x = 1.15, const std::string& lighting = "nominal") {
  return scenarioText(target_x, 0.0, 180.0, 0.0, lighting) + extra;
}

}  // namespace

TEST(Realism, ThinLensCircleOfConfusionMatchesTheLensEquation) {
  docking_sim::CameraEffects e;
  e.focal_length_mm = 3.0;
  e.f_number = 2.0;
  e.focus_distance_m = 0.9;
  e.pixel_pitch_um = 5.6;
  // Independently: image distance v(z) = 1 / (1/f - 1/z); the sensor sits at v(s); a point at z
  // focuses at v(z) and spreads to a disc of diameter A |v(z) - v(s)| / v(z) on the sensor.
  const double f = 3e-3, aperture = f / 2.0;
  auto v = [&](double z) { return 1.0 / (1.0 / f - 1.0 / z); };
  for (const double z : {0.3, 0.4, 0.9, 2.0, 6.0, 1e6}) {
    const double expected_px = aperture * std::abs(v(z) - v(0.9)) / v(z) / 5.6e-6;
    EXPECT_NEAR(docking_sim::circleOfConfusionPx(e, z), expected_px, 1e-9 + 1e-9 * expected_px) << z;
    EXPECT_NEAR(docking_sim::defocusSigmaPx(e, z), expected_px / 4.0, 1e-9) << z;
  }
  // The C270 default: about 1.1 px (sigma 0.28) at 0.4 m, nothing at the focus.
  EXPECT_NEAR(docking_sim::circleOfConfusionPx(e, 0.4), 1.12, 0.01);
  EXPECT_DOUBLE_EQ(docking_sim::circleOfConfusionPx(e, 0.9), 0.0);
  e.f_number = 0.0;  // a pinhole
  EXPECT_DOUBLE_EQ(docking_sim::circleOfConfusionPx(e, 0.4), 0.0);
}

TEST(Realism, OutOfFocusPlanesSpreadTheirEdgesByTheirCircleOfConfusion) {
  // Two black/white edges at two depths in one frame (so the per-pixel blend runs, not the uniform
  // path): top half at 0.4 m, bottom half at 2.5 m, lens focused at 0.8 m with a wide aperture.
  docking_sim::CameraEffects e = plainEffects();
  e.focal_length_mm = 3.0;
  e.f_number = 1.0;
  e.focus_distance_m = 0.8;
  e.pixel_pitch_um = 2.0;
  const double near_z = 0.4, far_z = 2.5, f = 550;  // sigma 1.41 and 0.96 px
  docking_sim::Scene scene;
  // Each half: dark left, bright right, the edge at x = 0 (image column 319.5).
  scene.addSurface(card(-2.0, 0.0, -2.0, 0.0, near_z, 40));
  scene.addSurface(card(0.0, 2.0, -2.0, 0.0, near_z, 220));
  scene.addSurface(card(-9.0, 0.0, 0.0, 9.0, far_z, 40));
  scene.addSurface(card(0.0, 9.0, 0.0, 9.0, far_z, 220));
  scene.update(Eigen::Isometry3d::Identity());
  docking_sim::CameraRenderer renderer(pinhole(f), docking_sim::Band::kVisible, e, quiet(), 1, noDistortion());
  const cv::Mat gray = toGray(renderer.render(scene, Eigen::Isometry3d::Identity()));
  for (const auto& [z, row] : {std::make_pair(near_z, 100), std::make_pair(far_z, 380)}) {
    const double sigma = docking_sim::defocusSigmaPx(e, z);
    ASSERT_GT(sigma, 0.7) << "test setup: the planes must be visibly out of focus";
    // A sampled step's differences spread by the Gaussian and by the pixel (1/12 px^2).
    const double expected = std::sqrt(sigma * sigma + 1.0 / 12.0);
    EXPECT_NEAR(edgeSpreadAlongRow(gray, row, 300, 340), expected, 0.08 * expected) << "plane at " << z << " m";
  }
  // In focus: the same scene at f/0 keeps the edge a one-pixel step.
  docking_sim::CameraRenderer sharp(pinhole(f), docking_sim::Band::kVisible, plainEffects(), quiet(), 1, noDistortion());
  EXPECT_LT(edgeSpreadAlongRow(toGray(sharp.render(scene, Eigen::Isometry3d::Identity())), 100, 300, 340), 0.35);
}

TEST(Realism, MotionBlurSpreadsAlongTheMotionByTheDisplacementAndNotAcross) {
  // A dark card with a bright square on it moves sideways at 1 m while the camera exposes 30 ms.
  docking_sim::CameraEffects e = plainEffects();
  e.motion_blur_enabled = true;
  e.motion_blur_max_subframes = 64;
  e.exposure_time_s = 0.03;
  const double f = 550, z = 1.0, speed = 0.5;  // 550 * 0.5 * 0.03 / 1 = 8.25 px
  docking_sim::Scene scene;
  docking_sim::Surface back = card(-3, 3, -3, 3, 1.5, 120);
  scene.addSurface(back);
  docking_sim::Surface dark = card(-0.2, 0.2, -0.2, 0.2, z, 30);
  dark.moves_with_target = true;
  docking_sim::Surface bright = card(-0.05, 0.05, -0.05, 0.05, z - 0.001, 230);
  bright.moves_with_target = true;
  scene.addSurface(dark);
  scene.addSurface(bright);
  docking_sim::ExposureMotion motion;
  motion.world_T_camera = [](double) { return Eigen::Isometry3d::Identity(); };
  motion.world_T_target_robot = [&](double dt) {
    Eigen::Isometry3d t = Eigen::Isometry3d::Identity();
    t.translation().x() = speed * dt;
    return t;
  };
  docking_sim::CameraRenderer renderer(pinhole(f), docking_sim::Band::kVisible, e, quiet(), 1, noDistortion());
  const cv::Mat gray = toGray(renderer.render(scene, motion));
  const double length = f * speed * e.exposure_time_s / z;
  const int n = renderer.lastExposure().subframes;
  EXPECT_NEAR(renderer.lastExposure().motion_px, length, 0.05 * length);
  EXPECT_EQ(n, static_cast<int>(std::ceil(length / docking_sim::kMotionBlurStepPx)));
  // n positions length / n apart: a discrete box of variance (length / n)^2 (n^2 - 1) / 12, plus the pixel's.
  const double step = length / n;
  const double expected = std::sqrt(step * step * (n * n - 1) / 12.0 + 1.0 / 12.0);
  // The bright square's left edge (x = -0.05 m -> column 292) along the motion; its top edge across it.
  EXPECT_NEAR(edgeSpreadAlongRow(gray, 240, 275, 310), expected, 0.1 * expected);
  EXPECT_LT(edgeSpreadAlongColumn(gray, 319, 200, 230), 0.35) << "no blur across the motion";

  // A still scene: one sub-frame, the same image as the instant render.
  motion.world_T_target_robot = [](double) { return Eigen::Isometry3d::Identity(); };
  docking_sim::CameraRenderer still(pinhole(f), docking_sim::Band::kVisible, e, quiet(), 1, noDistortion());
  const cv::Mat blurred_still = still.render(scene, motion).clone();
  EXPECT_EQ(still.lastExposure().subframes, 1);
  EXPECT_LT(still.lastExposure().motion_px, 1e-9);
  docking_sim::CameraRenderer instant(pinhole(f), docking_sim::Band::kVisible, e, quiet(), 1, noDistortion());
  scene.update(Eigen::Isometry3d::Identity());
  EXPECT_EQ(cv::norm(blurred_still, instant.render(scene, Eigen::Isometry3d::Identity()), cv::NORM_INF), 0.0);
}

TEST(Realism, ScriptedChaserTurnBlursTheWholeFrameByRateTimesExposure) {
  // The chaser turning at 30 deg/s, a fixed 20 ms exposure: every static point moves ~f w T px.
  std::string text =
      scenarioWith("  camera_overrides: {visible: {exposure_time_s: 0.02, auto_exposure: {enabled: false}}}\n");
  const std::string still_chaser = "chaser: {x_m: 0.0, y_m: 0.0, yaw_deg: 0.0}";
  ASSERT_NE(text.find(still_chaser), std::string::npos);
  text.replace(text.find(still_chaser), still_chaser.size(),
               "chaser: {x_m: 0.0, y_m: 0.0, yaw_deg: 0.0, motion: {yaw_rate_deg_s: 30.0, reverse_every_s: 0.0}}");
  const std::string path = writeTempFile("turn", text);
  docking_sim::Simulation sim(files(path));
  EXPECT_EQ(sim.wheelCommand(true, {0.0, 0.0, 0.0}), docking_sim::CommandResult::kIgnoredScripted);
  for (int i = 0; i < 100; ++i) sim.advance(0.005);  // 0.5 s: the motors have settled
  EXPECT_NEAR(sim.chaser().twist().wz, 30.0 * M_PI / 180.0, 1e-3);
  sim.render(RobotModel::kStereoLeft);
  const auto& x = sim.renderer(RobotModel::kStereoLeft).lastExposure();
  const double expected = 550.0 * (30.0 * M_PI / 180.0) * 0.02;  // ~5.8 px at the image centre, a bit more off it
  EXPECT_GT(x.motion_px, expected * 0.99);
  EXPECT_LT(x.motion_px, expected * 1.5);
  EXPECT_EQ(x.subframes, static_cast<int>(std::ceil(x.motion_px / docking_sim::kMotionBlurStepPx)));
  docking_sim::ChaserMotionSpec sway{1.0, 2.0};
  EXPECT_EQ(sway.yawRateAt(0.5), 1.0);
  EXPECT_EQ(sway.yawRateAt(1.5), -1.0);
  EXPECT_EQ(sway.yawRateAt(3.5), 1.0);
}

TEST(Realism, AutoExposureReachesTheTargetInTheDarkWithGainAndNoiseUp) {
  // The dark room; the visible camera may use 40x gain, so the target mean is reachable.
  const std::string path = writeTempFile(
      "ae_dark", scenarioWith("  camera_overrides: {visible: {auto_exposure: {max_gain: 40.0}}}\n", 1.15, "dark"));
  docking_sim::Simulation sim(files(path));
  const int cam = RobotModel::kStereoLeft;
  sim.render(cam);
  const auto& e = sim.renderer(cam).effects();
  const auto& x = sim.renderer(cam).lastExposure();
  EXPECT_NEAR(x.measured_mean, e.ae_target_mean, 0.05 * e.ae_target_mean);
  EXPECT_DOUBLE_EQ(x.exposure_time_s, e.ae_max_exposure_s) << "the longest exposure before any gain";
  EXPECT_GT(x.gain, 5.0);
  // Noise scales with the gain. Measured where nothing clips: a scene that needs ~6x gain (its lighting
  // defined at a 200 ms exposure, 33 ms at most): two frames of it differ by noise only.
  docking_sim::Simulation dim(files(writeTempFile(
      "ae_dim", scenarioWith("  camera_overrides: {visible: {exposure_time_s: 0.2, auto_exposure: {max_gain: 40.0}}}\n"))));
  const cv::Mat dim_a = dim.render(cam).clone();
  const double gain = dim.renderer(cam).lastExposure().gain;
  EXPECT_GT(gain, 4.0);
  EXPECT_NEAR(dim.renderer(cam).lastExposure().measured_mean, e.ae_target_mean, 0.05 * e.ae_target_mean);
  cv::Mat diff;
  cv::subtract(dim_a, dim.render(cam), diff, cv::noArray(), CV_32F);
  cv::Scalar mean, stddev;
  cv::meanStdDev(diff.reshape(1), mean, stddev);
  const double sigma = stddev[0] / std::sqrt(2.0);
  const double expected = dim.lighting().visible.noise_sigma * gain;
  EXPECT_NEAR(sigma, expected, 0.1 * expected);
  // The same camera in nominal light: gain 1, less exposure, the nominal noise.
  docking_sim::Simulation lit(files(writeTempFile("ae_lit", scenarioWith(""))));
  lit.render(cam);
  EXPECT_DOUBLE_EQ(lit.renderer(cam).lastExposure().gain, 1.0);
  EXPECT_LT(lit.renderer(cam).lastExposure().exposure_time_s, x.exposure_time_s);
}

TEST(Realism, SpecularHighlightLandsWhereTheMirrorDirectionMeetsTheCamera) {
  // A glossy grey plane at z = 1 m facing the camera; the light travels along d (from behind the
  // camera, a little off axis). Mirror: the highlight sits where the view ray is d reflected, i.e.
  // at the plane point p with (0 - p) parallel to reflect(d): p = (-dx/dz, -dy/dz, 1) for d = (dx, dy, dz).
  const Eigen::Vector3d d = Eigen::Vector3d(0.2, 0.1, 1.0).normalized();
  docking_sim::CameraEffects e = plainEffects();
  e.specular_strength = 0.5;
  e.specular_shininess = 300;
  docking_sim::Scene scene;
  docking_sim::Surface plane = card(-2, 2, -2, 2, 1.0, 60);
  plane.glossy = true;
  scene.addSurface(plane);
  scene.setLighting(quiet(), d, 0.45, e, e);
  scene.update(Eigen::Isometry3d::Identity());
  const double f = 550;
  docking_sim::CameraRenderer renderer(pinhole(f), docking_sim::Band::kVisible, e, quiet(), 1, noDistortion());
  const cv::Mat gray = toGray(renderer.render(scene, Eigen::Isometry3d::Identity()));
  double lo, hi;
  cv::minMaxLoc(gray, &lo, &hi);
  // The lobe's top (a plateau of rounded grey levels): the centroid of the pixels within 10 of the peak.
  cv::Mat top;
  cv::compare(gray, hi - 10, top, cv::CMP_GE);
  const cv::Moments m = cv::moments(top, true);
  const cv::Point2d at(m.m10 / m.m00, m.m01 / m.m00);
  const cv::Point2d expected(319.5 - f * d.x() / d.z(), 239.5 - f * d.y() / d.z());
  EXPECT_LT(cv::norm(at - expected), 1.0) << "peak at " << at << ", mirror predicts " << expected;
  EXPECT_GT(hi - lo, 80.0) << "a visible highlight";
  // Not glossy: flat.
  scene = docking_sim::Scene();
  plane.glossy = false;
  scene.addSurface(plane);
  scene.setLighting(quiet(), d, 0.45, e, e);
  scene.update(Eigen::Isometry3d::Identity());
  cv::minMaxLoc(toGray(renderer.render(scene, Eigen::Isometry3d::Identity())), &lo, &hi);
  EXPECT_LE(hi - lo, 1.0);
}

TEST(Realism, ExtraClutterAddsTexturedObjectsThatShowWithManyCorners) {
  // A busy box 2 m ahead and 0.8 m to the left of the camera (the target is far behind it).
  const std::string box = "  extra_clutter:\n    - {name: busy_box, xy_m: [2.1, 0.85], yaw_deg: 0, size_m: [0.5, 0.6, 1.2], "
                          "material: MATERIAL, color_bgr: [150, 150, 150]}\n";
  auto make = [&](const std::string& material) {
    std::string text = box;
    text.replace(text.find("MATERIAL"), 8, material);
    return docking_sim::Simulation(files(writeTempFile("clutter_" + material, scenarioWith(text, 6.15))));
  };
  docking_sim::Simulation plain(files(writeTempFile("clutter_none", scenarioWith("", 6.15))));
  docking_sim::Simulation busy = make("busy");
  EXPECT_EQ(busy.scene().surfaces().size(), plain.scene().surfaces().size() + 5) << "four sides and a top";
  docking_sim::Simulation plastic = make("plastic");
  // Where the box's front face shows: its centre (2.1 - 0.25, 0.85, 0.6) in the left camera.
  const int cam = RobotModel::kStereoLeft;
  const Eigen::Vector3d c = busy.worldTCamera(cam).inverse() * Eigen::Vector3d(1.85, 0.85, 0.6);
  const cv::Point centre(cvRound(550 * c.x() / c.z() + 319.5), cvRound(550 * c.y() / c.z() + 239.5));
  const cv::Rect roi(centre.x - 40, centre.y - 40, 80, 80);
  // Corners over the whole frame (quality relative to the frame's strongest), counted on the box.
  auto corners = [&](docking_sim::Simulation& sim) {
    std::vector<cv::Point2f> found;
    cv::goodFeaturesToTrack(toGray(sim.render(cam)), found, 3000, 0.05, 3);
    return std::count_if(found.begin(), found.end(), [&](const cv::Point2f& p) { return roi.contains(p); });
  };
  const auto busy_corners = corners(busy), plain_box_corners = corners(plastic);
  EXPECT_GT(busy_corners, 3 * plain_box_corners + 10) << busy_corners << " vs " << plain_box_corners;
  EXPECT_GT(cv::norm(busy.render(cam)(roi), plain.render(cam)(roi), cv::NORM_L1), 0.0) << "the box shows";
}

TEST(Realism, CameraOverridesApplyPerBandAndBadValuesAreNamed) {
  const std::string good = writeTempFile(
      "overrides", scenarioWith("  camera_overrides:\n    visible: {blur_sigma_px: 1.5, optics: {f_number: 4.0}}\n"
                                "    ir: {led_radiance: 3.0, specular: {strength: 2.0}}\n"));
  docking_sim::Simulation sim(files(good));
  docking_sim::Simulation reference(files(writeTempFile("no_overrides", scenarioWith(""))));
  const auto& v = sim.renderer(RobotModel::kStereoLeft).effects();
  const auto& v0 = reference.renderer(RobotModel::kStereoLeft).effects();
  EXPECT_EQ(v.blur_sigma_px, 1.5);
  EXPECT_EQ(v.f_number, 4.0);
  EXPECT_EQ(v.focus_distance_m, v0.focus_distance_m) << "keys not overridden keep sim.yaml's value";
  EXPECT_EQ(sim.renderer(RobotModel::kStereoRight).effects().f_number, 4.0) << "both visible cameras";
  const auto& ir = sim.renderer(RobotModel::kIr).effects();
  EXPECT_EQ(ir.led_radiance, 3.0);
  EXPECT_EQ(ir.specular_strength, 2.0);
  EXPECT_EQ(ir.blur_sigma_px, reference.renderer(RobotModel::kIr).effects().blur_sigma_px);

  const std::pair<std::string, std::string> bad[] = {
      {"  camera_overrides: {visible: {optics: {f_number: -1.0}}}\n", "scenario.camera_overrides.visible.optics.f_number"},
      {"  camera_overrides: {visible: {blurr_sigma_px: 1.0}}\n", "scenario.camera_overrides.visible.blurr_sigma_px"},
      {"  camera_overrides: {visible: {led_radiance: 2.0}}\n", "scenario.camera_overrides.visible.led_radiance"},
      {"  camera_overrides: {uv: {exposure: 1.0}}\n", "scenario.camera_overrides.uv"},
      {"  camera_overrides: {ir: {auto_exposure: {enabled: maybe}}}\n", "scenario.camera_overrides.ir.auto_exposure.enabled"},
      {"  extra_clutter:\n    - {name: x, xy_m: [2, 1], yaw_deg: 0, size_m: [1, 1, 1], material: glass, color_bgr: [1, 2, 3]}\n",
       "scenario.extra_clutter[0].material"},
      {"  light_direction: [0, 0, 0]\n", "scenario.light_direction"},
  };
  for (const auto& [text, field] : bad) {
    const std::string path = writeTempFile("bad_override", scenarioWith(text));
    try {
      docking_sim::loadScenario(path);
      ADD_FAILURE() << "no ConfigError for " << text;
    } catch (const docking_sim::ConfigError& error) {
      const std::string what = error.what();
      EXPECT_NE(what.find(path), std::string::npos) << what;
      EXPECT_NE(what.find(field), std::string::npos) << what << " should name " << field;
    }
  }
}

TEST(Realism, EveryShippedRealisticScenarioLoads) {
  int found = 0;
  for (const auto& entry : std::filesystem::directory_iterator(docking_sim_test::configDir() + "/scenarios")) {
    const std::string name = entry.path().filename().string();
    if (name.rfind("eval_real_", 0) != 0) continue;
    ++found;
    EXPECT_NO_THROW(docking_sim::Simulation(files(entry.path().string()))) << name;
  }
  EXPECT_GE(found, 10);
}
