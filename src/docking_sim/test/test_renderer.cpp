// Renderer geometry: markers land where the pinhole model puts them, stereo disparity equals f*b/Z,
// nearer surfaces hide farther ones (whatever the drawing order), the LEDs light up in IR as
// saturated, lens-blurred spots at their projections.
#include <gtest/gtest.h>

#include <opencv2/calib3d.hpp>
#include <opencv2/imgproc.hpp>

#include <cmath>
#include <cstdio>

#include "docking_sim/renderer.h"
#include "docking_sim/simulation.h"
#include "test_helpers.h"

using docking_sim::RobotModel;
using docking_sim_test::files;
using docking_sim_test::scenarioText;
using docking_sim_test::writeTempFile;

namespace {

/// An undistorted pinhole camera: focal length f px, principal point (cx, cy).
/// A 20 cm grey (90) card facing the camera, 1 cm in front of `centre` (camera frame): it must hide
/// whatever lies at `centre`.
docking_sim::Surface greyCardInFrontOf(const Eigen::Vector3d& centre) {
  docking_sim::Surface card;
  card.origin = centre + Eigen::Vector3d(-0.1, -0.1, -0.01);
  card.edge_u = Eigen::Vector3d(0.2, 0, 0);
  card.edge_v = Eigen::Vector3d(0, 0.2, 0);
  card.color = cv::Vec3b(90, 90, 90);
  return card;
}

docking_sim::CameraCalibration pinholeCalibration(int width, int height, double f, double cx, double cy) {
  docking_sim::CameraCalibration cal;
  cal.width = width;
  cal.height = height;
  cal.K = cv::Matx33d(f, 0, cx, 0, f, cy, 0, 0, 1);
  cal.D = {0, 0, 0, 0, 0};
  return cal;
}

docking_sim::RenderOptions clean() {
  docking_sim::RenderOptions o;
  o.distortion = false;
  o.effects = false;
  return o;
}

cv::Point2d project(const cv::Matx33d& K, const Eigen::Vector3d& p) {
  return {K(0, 0) * p.x() / p.z() + K(0, 2), K(1, 1) * p.y() / p.z() + K(1, 2)};
}

/// Centroid of the dark blob around `guess`: pixels darker than the midpoint of the window's range.
cv::Point2d darkCentroid(const cv::Mat& gray, cv::Point2d guess, int half) {
  const cv::Rect roi(static_cast<int>(guess.x) - half, static_cast<int>(guess.y) - half, 2 * half + 1, 2 * half + 1);
  const cv::Mat w = gray(roi);
  double lo, hi;
  cv::minMaxLoc(w, &lo, &hi);
  const double threshold = 0.5 * (lo + hi);
  double sx = 0, sy = 0, n = 0;
  for (int y = 0; y < w.rows; ++y) {
    for (int x = 0; x < w.cols; ++x) {
      if (w.at<uchar>(y, x) < threshold) {
        sx += x;
        sy += y;
        n += 1;
      }
    }
  }
  if (n == 0) return {-1, -1};
  return {roi.x + sx / n, roi.y + sy / n};
}

}  // namespace

TEST(Renderer, MarkersLandOnThePinholeProjection) {
  // Port 0.8 m ahead of base_link, turned 20 deg: an oblique, perspective view of the face.
  const double yaw = 200.0 * M_PI / 180.0;
  const double port_x = 0.8;
  const std::string path =
      writeTempFile("markers", scenarioText(port_x - 0.15 * std::cos(yaw), -0.15 * std::sin(yaw), 200.0));
  docking_sim::Simulation sim(files(path), clean());
  const cv::Mat image = sim.render(RobotModel::kStereoLeft);
  cv::Mat gray;
  cv::cvtColor(image, gray, cv::COLOR_BGR2GRAY);
  const auto& cam = sim.robot().cameras[RobotModel::kStereoLeft];
  const Eigen::Isometry3d camera_T_port = sim.truthInCamera(RobotModel::kStereoLeft).camera_T_port;
  const double radius_px = cam.calibration.K(0, 0) * sim.target().marker_radius_m / camera_T_port.translation().z();
  ASSERT_GT(radius_px, 4.0);
  for (std::size_t i = 0; i < sim.target().markers_m.size(); ++i) {
    const cv::Point2d predicted = project(cam.calibration.K, camera_T_port * sim.target().markers_m[i]);
    const cv::Point2d found = darkCentroid(gray, predicted, static_cast<int>(radius_px * 1.5));
    EXPECT_LE(std::hypot(found.x - predicted.x, found.y - predicted.y), 0.5)
        << "marker " << i << " predicted " << predicted << " found " << found;
  }
}

TEST(Renderer, IrLedsAreBrightAtTheMarkersInTheDark) {
  // Fixed exposure on the visible camera (auto-exposure would lift the dark room: test_realism.cpp).
  const std::string path = writeTempFile("leds", scenarioText(1.15, 0.0, 180.0, 0.0, "dark") +
                                                     "  camera_overrides: {visible: {auto_exposure: {enabled: false}}}\n");
  docking_sim::RenderOptions options;  // the full pipeline: distortion and effects
  docking_sim::Simulation sim(files(path), options);
  const cv::Mat ir = sim.render(RobotModel::kIr);
  ASSERT_EQ(ir.type(), CV_8UC1);
  const auto& cam = sim.robot().cameras[RobotModel::kIr];
  const Eigen::Isometry3d camera_T_port = sim.truthInCamera(RobotModel::kIr).camera_T_port;
  std::vector<cv::Point2f> ideal, distorted;
  for (const auto& m : sim.target().markers_m) {
    const cv::Point2d p = project(cam.calibration.K, camera_T_port * m);
    ideal.emplace_back(static_cast<float>((p.x - cam.calibration.K(0, 2)) / cam.calibration.K(0, 0)),
                       static_cast<float>((p.y - cam.calibration.K(1, 2)) / cam.calibration.K(1, 1)));
  }
  // Distort the normalised points with the camera's own model to find where the LEDs must appear.
  std::vector<cv::Point3f> rays;
  for (const auto& p : ideal) rays.emplace_back(p.x, p.y, 1.0f);
  cv::projectPoints(rays, cv::Vec3d(0, 0, 0), cv::Vec3d(0, 0, 0), cv::Mat(cam.calibration.K),
                    cv::Mat(cam.calibration.D), distorted);
  const double background = cv::mean(ir)[0];
  EXPECT_LT(background, 40.0) << "the dark room must look dark in IR";
  for (const auto& p : distorted) {
    const uchar led = ir.at<uchar>(cvRound(p.y), cvRound(p.x));
    EXPECT_GT(led, 200) << "LED at " << p << " not bright";
  }
  // The visible camera at its nominal exposure sees almost nothing.
  EXPECT_LT(cv::mean(sim.render(RobotModel::kStereoLeft))[0], 15.0);
}

TEST(Renderer, StereoDisparityMatchesFocalTimesBaselineOverDepth) {
  // Face square to the cameras: its plane is at constant depth, so the disparity is f*b/Z everywhere.
  const std::string path = writeTempFile("disparity", scenarioText(1.05, 0.0, 180.0));
  docking_sim::Simulation sim(files(path), clean());
  cv::Mat left, right;
  cv::cvtColor(sim.render(RobotModel::kStereoLeft), left, cv::COLOR_BGR2GRAY);
  cv::cvtColor(sim.render(RobotModel::kStereoRight), right, cv::COLOR_BGR2GRAY);
  const auto& cam = sim.robot().cameras[RobotModel::kStereoLeft];
  const Eigen::Isometry3d camera_T_port = sim.truthInCamera(RobotModel::kStereoLeft).camera_T_port;
  const double depth = camera_T_port.translation().z();
  const double baseline = (sim.robot().cameras[RobotModel::kStereoLeft].base_T_camera.translation() -
                           sim.robot().cameras[RobotModel::kStereoRight].base_T_camera.translation())
                              .norm();
  const double expected = cam.calibration.K(0, 0) * baseline / depth;

  // Block matching with a parabola through the best SAD: several textured patches on the face.
  const Eigen::Vector3d patch_centres[3] = {{0, 0.06, -0.06}, {0, -0.05, -0.08}, {0, 0.06, 0.02}};
  for (const auto& c : patch_centres) {
    const cv::Point2d p = project(cam.calibration.K, camera_T_port * c);
    const int half = 12;
    const cv::Rect patch_rect(cvRound(p.x) - half, cvRound(p.y) - half, 2 * half + 1, 2 * half + 1);
    const cv::Mat patch = left(patch_rect);
    std::vector<double> sad;
    const int max_d = static_cast<int>(expected) + 15;
    for (int d = 0; d <= max_d; ++d) {
      cv::Mat diff;
      cv::absdiff(patch, right(patch_rect - cv::Point(d, 0)), diff);
      sad.push_back(cv::sum(diff)[0]);
    }
    const auto best = static_cast<int>(std::min_element(sad.begin(), sad.end()) - sad.begin());
    ASSERT_GT(best, 0);
    ASSERT_LT(best, max_d);
    const double a = sad[best - 1], b = sad[best], cc = sad[best + 1];
    const double measured = best + 0.5 * (a - cc) / (a - 2 * b + cc);
    EXPECT_NEAR(measured, expected, 0.5) << "patch at " << p << ", depth " << depth;
  }
}

TEST(Renderer, NearerSurfacesOccludeFartherOnesWhateverTheDrawingOrder) {
  const docking_sim::CameraCalibration cal = pinholeCalibration(160, 120, 100, 79.5, 59.5);
  docking_sim::LightingScenario light;
  light.visible.noise_sigma = 0;
  docking_sim::CameraEffects effects;
  effects.blur_sigma_px = 0;
  effects.vignetting = 0;
  docking_sim::CameraRenderer renderer(cal, docking_sim::Band::kVisible, effects, light, 1, clean());

  auto quad = [](double x0, double x1, double y0, double y1, double z, cv::Vec3b color) {
    docking_sim::Surface s;
    s.origin = Eigen::Vector3d(x0, y0, z);
    s.edge_u = Eigen::Vector3d(x1 - x0, 0, 0);
    s.edge_v = Eigen::Vector3d(0, y1 - y0, 0);
    s.color = color;
    return s;
  };
  const cv::Vec3b red(0, 0, 200), blue(200, 0, 0), green(0, 200, 0);
  docking_sim::Scene scene;
  // Far: a small red square on the axis at 2 m (its centre is the nearest of all centres).
  scene.addSurface(quad(-0.6, 0.6, -0.6, 0.6, 2.0, red));
  // Near: a huge blue plane at 1 m whose centre lies far off to the side, so a painter's sort by
  // centre would draw it last and a naive renderer without depth would get it right by luck ... or
  // first: only the z-buffer makes both orders correct. It covers the axis.
  scene.addSurface(quad(-0.2, 40.0, -0.1, 0.1, 1.0, blue));
  // Farther still: a green backdrop at 5 m.
  scene.addSurface(quad(-10, 10, -10, 10, 5.0, green));
  scene.update(Eigen::Isometry3d::Identity());
  const cv::Mat image = renderer.render(scene, Eigen::Isometry3d::Identity()).clone();

  EXPECT_EQ(image.at<cv::Vec3b>(60, 80)[0], blue[0]) << "the near blue band must hide the red square";
  EXPECT_EQ(image.at<cv::Vec3b>(60, 80)[2], 0);
  // Above the blue band (row 46: y = -0.135 m at 1 m, -0.27 m at 2 m): red in front of green.
  EXPECT_EQ(image.at<cv::Vec3b>(46, 80)[2], red[2]);
  // Outside the red square: the green backdrop.
  EXPECT_EQ(image.at<cv::Vec3b>(10, 10)[1], green[1]);
  // The blue band's left end at x = -0.2 m, 1 m deep -> column 59.5: left of it at row 60 is red.
  EXPECT_EQ(image.at<cv::Vec3b>(60, 58)[2], red[2]);
  EXPECT_EQ(image.at<cv::Vec3b>(60, 61)[0], blue[0]);
}

TEST(Renderer, DeterministicForASeedAndNoisyAcrossFrames) {
  const std::string path = writeTempFile("determinism", scenarioText(2.15, 0.0, 180.0));
  docking_sim::Simulation a(files(path)), b(files(path));
  const cv::Mat fa = a.render(RobotModel::kStereoLeft).clone();
  const cv::Mat fb = b.render(RobotModel::kStereoLeft).clone();
  EXPECT_EQ(cv::norm(fa, fb, cv::NORM_L1), 0.0);
  a.advance(1.0 / 30);
  const cv::Mat fa2 = a.render(RobotModel::kStereoLeft);
  EXPECT_GT(cv::norm(fa, fa2, cv::NORM_L1), 0.0) << "sensor noise must change from frame to frame";
}

namespace {

/// A 640x480 pinhole camera with the principal point off the pixel grid (no distortion, no effects).
docking_sim::CameraRenderer pinholeRenderer(docking_sim::Band band) {
  const docking_sim::CameraCalibration cal = pinholeCalibration(640, 480, 540, 319.3, 240.6);
  docking_sim::LightingScenario light;
  light.visible.noise_sigma = 0;
  light.ir.noise_sigma = 0;
  light.led_intensity = 1.0;
  docking_sim::CameraEffects effects;
  effects.blur_sigma_px = 0;
  effects.vignetting = 0;
  return docking_sim::CameraRenderer(cal, band, effects, light, 1, clean());
}

/// Centroid of |image - background| in a square window of half size `half` around `centre`.
cv::Point2d contrastCentroid(const cv::Mat& gray, cv::Point2d centre, int half, double background) {
  double sx = 0, sy = 0, sw = 0;
  for (int y = cvRound(centre.y) - half; y <= cvRound(centre.y) + half; ++y) {
    for (int x = cvRound(centre.x) - half; x <= cvRound(centre.x) + half; ++x) {
      const double w = std::abs(gray.at<uchar>(y, x) - background);
      sx += w * x;
      sy += w * y;
      sw += w;
    }
  }
  return sw > 0 ? cv::Point2d(sx / sw, sy / sw) : cv::Point2d(-1, -1);
}

/// A face-on textured square of side `side` m with its top-left corner at `origin` (camera frame),
/// alone in the scene, through pinholeRenderer: the grey image.
cv::Mat renderTexturedSquare(const Eigen::Vector3d& origin, double side,
                             const std::shared_ptr<const docking_sim::Texture>& tex, bool bilinear) {
  auto renderer = pinholeRenderer(docking_sim::Band::kVisible);
  docking_sim::Surface square;
  square.origin = origin;
  square.edge_u = Eigen::Vector3d(side, 0, 0);
  square.edge_v = Eigen::Vector3d(0, side, 0);
  square.texture = tex;
  square.bilinear = bilinear;
  docking_sim::Scene scene;
  scene.addSurface(square);
  scene.update(Eigen::Isometry3d::Identity());
  cv::Mat gray;
  cv::cvtColor(renderer.render(scene, Eigen::Isometry3d::Identity()), gray, cv::COLOR_BGR2GRAY);
  return gray;
}

}  // namespace

// A face-on textured square (0.2 m, 512x512 texels: mip levels 1 to 3 at these distances) with a dark
// Gaussian blob off its centre: the blob's image centroid must be the pinhole projection of the
// blob's centre. Mip levels built with cv::pyrDown (texel j of level L centred at texel 2^L j of
// level 0, not at 2^L (j + 0.5) - 0.5) moved it by (2^L - 1) / 2 texels of level 0: 0.2-0.4 px here.
TEST(Renderer, TextureLandsOnThePinholeProjectionAtEveryMipLevel) {
  const int size = 512;
  // A blob wide enough (several texels at level 3) that nearest-texel sampling jitter stays small.
  const double blob_s = 0.43, blob_t = 0.56, sigma = 0.07;  // texture coordinates (fractions)
  cv::Mat texture(size, size, CV_8UC3);
  for (int v = 0; v < size; ++v) {
    for (int u = 0; u < size; ++u) {
      // Texel (u, v) covers [u, u + 1) / size: its centre is at (u + 0.5) / size.
      const double ds = (u + 0.5) / size - blob_s, dt = (v + 0.5) / size - blob_t;
      const double value = 220.0 - 190.0 * std::exp(-(ds * ds + dt * dt) / (2 * sigma * sigma));
      texture.at<cv::Vec3b>(v, u) = cv::Vec3b::all(cv::saturate_cast<uchar>(value));
    }
  }
  const auto tex = docking_sim::makeTexture(texture, false);
  ASSERT_GE(tex->blocked.size(), 4u);
  const double side = 0.2;
  for (const double z : {0.5, 1.0, 1.4, 2.0}) {
    for (const double lateral : {-0.013, 0.021}) {
      const Eigen::Vector3d origin(lateral - side / 2, 0.7 * lateral - side / 2, z);
      const cv::Mat gray = renderTexturedSquare(origin, side, tex, false);
      const cv::Matx33d K(540, 0, 319.3, 0, 540, 240.6, 0, 0, 1);
      const Eigen::Vector3d centre = origin + Eigen::Vector3d(blob_s * side, blob_t * side, 0.0);
      const cv::Point2d predicted = project(K, centre);
      const double sigma_px = 540 * sigma * side / z;
      const cv::Point2d found = contrastCentroid(gray, predicted, static_cast<int>(std::ceil(4.5 * sigma_px)), 220.0);
      EXPECT_LE(std::hypot(found.x - predicted.x, found.y - predicted.y), 0.05)
          << "at " << z << " m, lateral " << lateral << ": predicted " << predicted << " found " << found;
    }
  }
}

namespace {

/// Where a dark-to-bright vertical step lies along image row y, from x0 to x1 (pixel centres), as a
/// camera that integrates light over each pixel would place it: the bright share of the row segment.
double stepEdgeX(const cv::Mat& gray, int y, int x0, int x1, double dark, double bright) {
  double bright_px = 0.0;
  for (int x = x0; x <= x1; ++x) bright_px += (gray.at<uchar>(y, x) - dark) / (bright - dark);
  return x1 + 0.5 - bright_px;
}

/// The largest error of the step's image position over lateral moves of 0 .. 1 px in eighths: a
/// surface whose texture (64 texels, each ~1 px at 1 m) steps from dark to bright at its middle.
double worstStepEdgeErrorPx(bool bilinear) {
  cv::Mat texture(64, 64, CV_8UC3);
  texture.colRange(0, 32).setTo(cv::Scalar::all(30));
  texture.colRange(32, 64).setTo(cv::Scalar::all(220));
  const auto tex = docking_sim::makeTexture(texture, false);
  const double f = 540.0, z = 1.0, side = 64.0 / f * 1.03;  // texels a little wider than a pixel
  double worst = 0.0;
  for (int eighth = 0; eighth <= 8; ++eighth) {
    const Eigen::Vector3d origin(eighth / 8.0 / f * z - side / 2, -side / 2, z);
    const cv::Mat gray = renderTexturedSquare(origin, side, tex, bilinear);
    const cv::Matx33d K(f, 0, 319.3, 0, f, 240.6, 0, 0, 1);
    const double predicted = project(K, origin + Eigen::Vector3d(0.5 * side, 0.5 * side, 0.0)).x;
    const int x = static_cast<int>(std::lround(predicted));
    worst = std::max(worst, std::abs(stepEdgeX(gray, 240, x - 10, x + 10, 30.0, 220.0) - predicted));
  }
  return worst;
}

}  // namespace

// A camera integrates light over each pixel, so an edge in a print moves smoothly as the print moves
// by fractions of a pixel. Nearest-texel sampling moves it in whole pixels: on the target's fine print
// that jitter beats with the pixel grid across the face into a warp (still poses 0.5 deg off at 1.4 m).
// The target's surfaces (Surface::bilinear) must follow sub-pixel moves; the nearest texel must not,
// which shows this test can tell the two apart.
TEST(Renderer, BilinearTextureFollowsSubPixelMoves) {
  const double bilinear = worstStepEdgeErrorPx(true), nearest = worstStepEdgeErrorPx(false);
  std::printf("step edge error: bilinear %.3f px, nearest %.3f px\n", bilinear, nearest);
  EXPECT_LE(bilinear, 0.06);
  EXPECT_GE(nearest, 0.3);
}

// An emissive disc decal (a 24-gon, as the LEDs were drawn before they became light spots) in the
// plane of a dark face: its intensity centroid must be the projection of its centre to 0.05 px (a
// hard-edged disc was off by up to 0.3 px), it must show although it lies exactly in the face's
// plane, and a nearer surface hides it.
TEST(Renderer, LedDiscCentroidIsItsProjectedCentre) {
  const cv::Matx33d K(540, 0, 319.3, 0, 540, 240.6, 0, 0, 1);
  auto disc = [](const Eigen::Vector3d& centre, double r) {
    docking_sim::Surface s;
    s.origin = centre;
    s.edge_u = Eigen::Vector3d(r, 0, 0);
    s.edge_v = Eigen::Vector3d(0, r, 0);
    s.outline.clear();
    for (int k = 0; k < 24; ++k) {
      const double a = 2 * M_PI * k / 24;
      s.outline.emplace_back(std::cos(a), std::sin(a));
    }
    s.color = cv::Vec3b(255, 255, 255);
    s.bands = docking_sim::kInfraredBand;
    s.emissive = true;
    s.decal = true;
    return s;
  };
  int case_index = 0;
  for (const double z : {0.6, 1.0, 2.0, 3.0}) {
    for (int k = 0; k < 3; ++k, ++case_index) {
      // Centres at varied sub-pixel phases; a face turned 25 deg about y (an oblique plane).
      const Eigen::Vector3d centre(0.0123 * (k - 1) + 0.0007 * case_index, -0.0091 * k + 0.0011 * case_index, z);
      const Eigen::Matrix3d tilt = Eigen::AngleAxisd(25.0 * M_PI / 180.0, Eigen::Vector3d::UnitY()).toRotationMatrix();
      docking_sim::Surface face;
      face.origin = centre - tilt * Eigen::Vector3d(0.1, 0.1, 0);
      face.edge_u = tilt * Eigen::Vector3d(0.2, 0, 0);
      face.edge_v = tilt * Eigen::Vector3d(0, 0.2, 0);
      face.color = cv::Vec3b(40, 40, 40);
      docking_sim::Surface led = disc(centre, 0.005);
      led.edge_u = tilt * led.edge_u;
      led.edge_v = tilt * led.edge_v;
      docking_sim::Scene scene;
      scene.addSurface(led);  // before the face in the list: the decal still draws over it
      scene.addSurface(face);
      scene.update(Eigen::Isometry3d::Identity());
      auto renderer = pinholeRenderer(docking_sim::Band::kInfrared);
      const cv::Mat ir = renderer.render(scene, Eigen::Isometry3d::Identity()).clone();
      const cv::Point2d predicted = project(K, centre);
      const int half = static_cast<int>(std::ceil(540 * 0.005 / z)) + 3;
      const double background = ir.at<uchar>(cvRound(predicted.y) + half + 1, cvRound(predicted.x));  // the face
      EXPECT_GT(ir.at<uchar>(cvRound(predicted.y), cvRound(predicted.x)), background + 60) << "z " << z;
      const cv::Point2d found = contrastCentroid(ir, predicted, half, background);
      // Area sampling (what a pixel does) moves the centroid of a shape only a few pixels wide by up
      // to ~0.125 px / its width: < 0.05 px from 1.35 px radius (2 m) on; at 3 m (0.9 px) 0.08 px.
      EXPECT_LE(std::hypot(found.x - predicted.x, found.y - predicted.y), z < 2.5 ? 0.05 : 0.08)
          << "at " << z << " m: predicted " << predicted << " found " << found;

      // A card 1 cm in front of the LED hides it.
      scene.addSurface(greyCardInFrontOf(centre));
      scene.update(Eigen::Isometry3d::Identity());
      const cv::Mat hidden = renderer.render(scene, Eigen::Isometry3d::Identity());
      EXPECT_EQ(hidden.at<uchar>(cvRound(predicted.y), cvRound(predicted.x)), 90)
          << "z " << z << ": the LED (255) must be hidden by the card (90)";
    }
  }
}

// The simulator's own scene (config/target.yaml, dark room, IR camera, clean render): the centroid of
// what the LEDs add (render with LEDs minus render with led_intensity 0) is, for every LED, the
// pinhole projection of its marker position in target.yaml, in an oblique view (20 deg) at 1 m, so
// the LEDs lie in the face plane (they were drawn 1-2 mm in front of it: 0.3 px off here).
TEST(Renderer, SceneLedsLandOnTheMarkerPositions) {
  const std::string path = writeTempFile("led_positions", scenarioText(1.15, 0.0, 180.0, 0.0, "dark"));
  docking_sim::Simulation sim(files(path), clean());
  const auto& cam = sim.robot().cameras[RobotModel::kIr];
  docking_sim::LightingScenario lit = sim.lighting(), unlit = sim.lighting();
  unlit.led_intensity = 0.0;
  // Target robot at the world origin; the camera 1 m in front of the port, 20 deg off its axis.
  const Eigen::Isometry3d port = sim.target().robot_T_port;
  const double angle = 20.0 * M_PI / 180.0;
  const Eigen::Vector3d out = port.linear() * Eigen::Vector3d(std::cos(angle), std::sin(angle), 0.0);
  Eigen::Isometry3d world_T_camera = Eigen::Isometry3d::Identity();
  const Eigen::Vector3d z_axis = -out, y_axis(0, 0, -1);
  world_T_camera.linear().col(0) = y_axis.cross(z_axis);
  world_T_camera.linear().col(1) = y_axis;
  world_T_camera.linear().col(2) = z_axis;
  world_T_camera.translation() = port.translation() + 1.0 * out;
  cv::Mat images[2];
  for (int k = 0; k < 2; ++k) {
    docking_sim::Scene scene(sim.settings(), sim.target(), k == 0 ? lit : unlit, 1);
    scene.update(Eigen::Isometry3d::Identity());
    docking_sim::CameraRenderer renderer(cam.calibration, docking_sim::Band::kInfrared, sim.settings().ir_effects,
                                         k == 0 ? lit : unlit, 1, clean());
    images[k] = renderer.render(scene, world_T_camera).clone();
  }
  cv::Mat added;
  cv::subtract(images[0], images[1], added);
  const Eigen::Isometry3d camera_T_port = world_T_camera.inverse() * port;
  const int half = static_cast<int>(std::ceil(cam.calibration.K(0, 0) * sim.target().led_radius_m * 2.2)) + 3;
  for (std::size_t i = 0; i < sim.target().markers_m.size(); ++i) {
    const cv::Point2d predicted = project(cam.calibration.K, camera_T_port * sim.target().markers_m[i]);
    ASSERT_GT(added.at<uchar>(cvRound(predicted.y), cvRound(predicted.x)), 150) << "LED " << i;
    const cv::Point2d found = contrastCentroid(added, predicted, half, 0.0);
    EXPECT_LE(std::hypot(found.x - predicted.x, found.y - predicted.y), 0.05)
        << "LED " << i << " predicted " << predicted << " found " << found;
  }
}

namespace {

/// A dark flat face at depth z facing the camera, with an LED (radius 5 mm, as target.yaml) on it.
docking_sim::Scene ledOnDarkFace(const Eigen::Vector3d& centre, double led_radiance) {
  docking_sim::Scene scene;
  docking_sim::Surface face;
  face.origin = centre + Eigen::Vector3d(-0.2, -0.2, 0.0);
  face.edge_u = Eigen::Vector3d(0.4, 0, 0);
  face.edge_v = Eigen::Vector3d(0, 0.4, 0);
  face.color = cv::Vec3b(20, 20, 20);
  scene.addSurface(face);
  docking_sim::Led led;
  led.centre = centre;
  led.normal = Eigen::Vector3d(0, 0, -1);  // towards the camera at the origin
  led.radius_m = 0.005;
  scene.addLed(led);
  docking_sim::LightingScenario light;
  docking_sim::CameraEffects ir;
  ir.led_radiance = led_radiance;
  scene.setLighting(light, Eigen::Vector3d(0, 0, 1), 1.0, docking_sim::CameraEffects(), ir);
  scene.update(Eigen::Isometry3d::Identity());
  return scene;
}

}  // namespace

// An LED at 4 m through the IR camera's full pipeline (its calibration with distortion, sim.yaml's
// led_radiance, lens blur; no noise): a saturated spot, above the IR detector's led_threshold (140)
// over a few pixels, centred within 0.5 px of the pinhole + distortion projection of the LED's
// centre, hidden by a card in front of it, and not seen by a visible camera.
TEST(Renderer, FarIrLedIsASaturatedSpotAtItsDistortedProjection) {
  const std::string path = writeTempFile("far_led", scenarioText(1.15, 0.0, 180.0, 0.0, "dark"));
  docking_sim::Simulation sim(files(path), clean());
  const docking_sim::CameraCalibration& cal = sim.robot().cameras[RobotModel::kIr].calibration;
  const docking_sim::CameraEffects effects = sim.settings().ir_effects;
  docking_sim::LightingScenario quiet;
  quiet.ir.noise_sigma = 0;
  quiet.visible.noise_sigma = 0;
  // Off axis (normalised 0.4, 0.25): barrel distortion moves it ~4 px from the pinhole projection.
  const Eigen::Vector3d centre(1.6, 1.0, 4.0);
  docking_sim::Scene scene = ledOnDarkFace(centre, effects.led_radiance);
  docking_sim::CameraRenderer renderer(cal, docking_sim::Band::kInfrared, effects, quiet, 1);
  const cv::Mat ir = renderer.render(scene, Eigen::Isometry3d::Identity()).clone();
  std::vector<cv::Point2f> predicted;
  cv::projectPoints(std::vector<cv::Point3f>{cv::Point3f(1.6f, 1.0f, 4.0f)}, cv::Vec3d(0, 0, 0), cv::Vec3d(0, 0, 0),
                    cv::Mat(cal.K), cv::Mat(cal.D), predicted);
  const cv::Point2d p(predicted[0].x, predicted[0].y);
  const cv::Rect window(cvRound(p.x) - 5, cvRound(p.y) - 5, 11, 11);
  double lo, hi;
  cv::minMaxLoc(ir(window), &lo, &hi);
  EXPECT_EQ(hi, 255.0) << "a far LED must saturate the sensor";
  EXPECT_GE(cv::countNonZero(ir(window) > 140), 4) << "too few pixels for the IR detector";
  const double background = ir.at<uchar>(cvRound(p.y) + 12, cvRound(p.x));  // the face
  EXPECT_LT(background, 40.0);
  const cv::Point2d found = contrastCentroid(ir, p, 5, background);
  EXPECT_LE(std::hypot(found.x - p.x, found.y - p.y), 0.5) << "predicted " << p << " found " << found;
  EXPECT_GT(std::hypot(p.x - (cal.K(0, 0) * 0.4 + cal.K(0, 2)), p.y - (cal.K(1, 1) * 0.25 + cal.K(1, 2))), 2.0)
      << "the test must exercise the distortion";

  // A card 1 cm in front of the LED hides it (the depth test at its centre).
  scene.addSurface(greyCardInFrontOf(centre));
  scene.update(Eigen::Isometry3d::Identity());
  cv::minMaxLoc(renderer.render(scene, Eigen::Isometry3d::Identity())(window), &lo, &hi);
  EXPECT_LT(hi, 100.0) << "the card (90 before vignetting) must hide the LED";

  // Seen from behind (the camera on the other side of the face), nothing shows.
  docking_sim::Scene behind = ledOnDarkFace(centre, effects.led_radiance);
  Eigen::Isometry3d world_T_camera = Eigen::Isometry3d::Identity();
  world_T_camera.linear() = Eigen::AngleAxisd(M_PI, Eigen::Vector3d::UnitY()).toRotationMatrix();
  world_T_camera.translation() = Eigen::Vector3d(0, 0, 8.0);
  cv::minMaxLoc(renderer.render(behind, world_T_camera), &lo, &hi);
  EXPECT_LT(hi, 40.0) << "an LED seen from behind must not light up";

  // The visible cameras do not see the IR LEDs.
  docking_sim::CameraRenderer visible(cal, docking_sim::Band::kVisible, effects, quiet, 1);
  cv::Mat grey;
  cv::cvtColor(visible.render(ledOnDarkFace(centre, effects.led_radiance), Eigen::Isometry3d::Identity()), grey,
               cv::COLOR_BGR2GRAY);
  cv::minMaxLoc(grey(window), &lo, &hi);
  EXPECT_LT(hi, 40.0);
}

// Below saturation the light an LED brings (the sum of what it adds to the image) is radiance x
// 255 x its projected disc area, so it falls as 1 / z^2, and its peak falls with distance.
TEST(Renderer, LedSpotBrightnessFallsWithDistanceAsItsProjectedArea) {
  const docking_sim::CameraCalibration cal = pinholeCalibration(640, 480, 520, 319.5, 239.5);
  docking_sim::LightingScenario quiet;
  quiet.ir.noise_sigma = 0;
  docking_sim::CameraEffects effects;
  effects.blur_sigma_px = 0.8;
  effects.vignetting = 0;
  docking_sim::RenderOptions no_distortion;
  no_distortion.distortion = false;
  constexpr double kRadiance = 0.5;  // peaks 180, 94, 32 grey levels at 1, 2, 4 m: unsaturated
  double last_peak = 1e9;
  for (const double z : {1.0, 2.0, 4.0}) {
    const Eigen::Vector3d centre(0.013, -0.021, z);
    docking_sim::CameraRenderer renderer(cal, docking_sim::Band::kInfrared, effects, quiet, 1, no_distortion);
    const cv::Mat with_led = renderer.render(ledOnDarkFace(centre, kRadiance), Eigen::Isometry3d::Identity()).clone();
    const cv::Mat without = renderer.render(ledOnDarkFace(centre, 0.0), Eigen::Isometry3d::Identity()).clone();
    cv::Mat added;
    cv::subtract(with_led, without, added, cv::noArray(), CV_32F);
    const cv::Point2d p = project(cal.K, centre);
    const cv::Rect window(cvRound(p.x) - 12, cvRound(p.y) - 12, 25, 25);
    const double light = cv::sum(added(window))[0];
    const double radius_px = 520 * 0.005 / z;
    const double expected = kRadiance * 255.0 * M_PI * radius_px * radius_px;
    EXPECT_NEAR(light / expected, 1.0, 0.06) << "at " << z << " m: " << light << " vs " << expected;
    EXPECT_EQ(cv::sum(added)[0], light) << "at " << z << " m: light outside the spot";
    double lo, hi;
    cv::minMaxLoc(added, &lo, &hi);
    EXPECT_LT(hi, 250.0) << "at " << z << " m the spot must stay below saturation for this test";
    EXPECT_LT(hi, last_peak) << "at " << z << " m";
    last_peak = hi;
  }
}

TEST(Renderer, CamerasRenderedInParallelEqualOneAfterAnother) {
  // A turning target: each exposure moves it across sub-frames in the scene a camera draws, so cameras
  // sharing one scene across threads would show each other's sub-frame poses.
  const std::string path = writeTempFile("parallel", scenarioText(1.2, 0.1, 180.0, 200.0));
  docking_sim::Simulation serial(files(path)), parallel(files(path));
  for (int step = 0; step < 3; ++step) {
    serial.advance(1.0 / 15);
    parallel.advance(1.0 / 15);
    std::array<cv::Mat, 3> expected;
    for (int cam = 0; cam < 3; ++cam) expected[static_cast<std::size_t>(cam)] = serial.render(cam).clone();
    const auto frames = parallel.renderCameras({{true, true, true}}, 3);
    for (int cam = 0; cam < 3; ++cam) {
      ASSERT_NE(frames[static_cast<std::size_t>(cam)], nullptr);
      EXPECT_EQ(cv::norm(*frames[static_cast<std::size_t>(cam)], expected[static_cast<std::size_t>(cam)], cv::NORM_INF), 0.0)
          << "camera " << cam << ", instant " << step;
    }
    EXPECT_GT(parallel.renderer(RobotModel::kStereoLeft).lastExposure().subframes, 1) << "the target must blur";
  }
  // Only the wanted cameras render.
  parallel.advance(1.0 / 15);
  const auto some = parallel.renderCameras({{true, false, true}}, 2);
  EXPECT_NE(some[RobotModel::kStereoLeft], nullptr);
  EXPECT_EQ(some[RobotModel::kStereoRight], nullptr);
  EXPECT_NE(some[RobotModel::kIr], nullptr);
}
