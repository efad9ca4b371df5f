// The far stage's tracking window (tracking_window.h, WindowRectifier::rectifyWindow, the detector's
// ImageWindow): its geometry; a window rectified alone is the whole image's rectification cut to it; the
// pipeline on a window (config/far_stereo.yaml's window settings, config/stereo_image_proc.yaml's matcher)
// finds the target where the whole image does; boxes beside it and crossing the window's edge are never
// reported as the target, and a window that cuts the target reports it not found, not found elsewhere.
#include <cmath>
#include <cstdint>
#include <optional>
#include <string>

#include <gtest/gtest.h>
#include <opencv2/calib3d.hpp>

#include "docking_perception/disparity/window_rectifier.h"
#include "docking_perception/disparity/disparity_detector.h"
#include "docking_perception/disparity/tracking_window.h"
#include "synthetic_stereo.h"

#include <docking_settings/config_error.h>
#include <docking_settings/setting_info.h>

namespace docking_perception {
namespace disparity {
namespace {

const std::string kConfigDir = DISPARITY_CONFIG_DIR;

TrackingWindowParams configuredWindow() { return testing::shippedFarStereoSettings(kConfigDir).window; }

testing::MatcherSettings fullMatcher() { return testing::loadMatcherSettings(kConfigDir + "/stereo_image_proc.yaml"); }

DetectorParams configuredParams() { return testing::shippedDetectorSettings(kConfigDir).detector; }

// The region the detector nodelet searches: the matcher's blind left band and stereo_image_proc's valid
// window (half the correlation window off the other three sides), as the DisparityImage states it.
cv::Rect nodeletRegion(const testing::MatcherSettings& settings, cv::Size size) {
  const int half = settings.correlation_window_size / 2;
  const cv::Rect valid_window(0, half, size.width - half - std::max(0, settings.min_disparity), size.height - 2 * half);
  return testing::matcherValidRegion(settings, size) & valid_window;
}

// The far stage on the whole image (window empty) or on `window` of it, as far_stereo_rectify, the
// matcher and the detector nodelet run it.
Detection detectOn(const testing::FarStagePair& pair, const std::optional<cv::Rect>& window,
                   bool tell_detector_it_is_a_window = true) {
  const testing::MatcherSettings settings = fullMatcher();
  auto matcher = testing::createMatcher(settings);
  const cv::Rect area = window ? *window : cv::Rect(cv::Point(0, 0), pair.left.size());
  const cv::Mat disparity = testing::computeDisparity(*matcher, pair.left(area).clone(), pair.right(area).clone());
  StereoGeometry geometry = pair.geometry;
  geometry.cx_px -= area.x;
  geometry.cy_px -= area.y;
  ImageWindow image_window;
  if (window && tell_detector_it_is_a_window) {
    image_window.offset = area.tl();
    image_window.full_size = pair.left.size();
  }
  return DisparityDetector(configuredParams(), loadTargetShape(kConfigDir + "/target.yaml"),
                           testing::shippedRig(kConfigDir))
      .detect(disparity, geometry, settings.min_disparity, testing::maxDisparity(settings),
              nodeletRegion(settings, disparity.size()), SearchHint(), image_window);
}

cv::Rect windowAround(const testing::FarStagePair& pair, const Eigen::Vector3d& port) {
  const auto window = trackingWindow(testing::projectionOf(pair.geometry), port, pair.left.size(), testing::matcherReachOf(fullMatcher()),
                                     configuredWindow());
  EXPECT_TRUE(window.has_value()) << "no window for a port at " << port.transpose();
  return window.value_or(cv::Rect());
}

TEST(TrackingWindow, SpansTheMockupAndTheMatchersReach) {
  const cv::Matx34d p(550.0, 0.0, 319.5, 0.0, 0.0, 550.0, 239.5, 0.0, 0.0, 0.0, 1.0, 0.0);
  const MatcherReach reach;  // 96 disparities, 15 px window
  TrackingWindowParams params;
  params.half_width_m = 0.8;
  params.half_height_m = 0.45;
  const Eigen::Vector3d port(0.3, 0.05, 4.0);
  const auto window = trackingWindow(p, port, cv::Size(640, 480), reach, params);
  ASSERT_TRUE(window.has_value());
  const double u = 550.0 * 0.3 / 4.0 + 319.5, v = 550.0 * 0.05 / 4.0 + 239.5;
  const double half_width = 550.0 * 0.8 / 4.0, half_height = 550.0 * 0.45 / 4.0;
  // Every pixel of the mockup's extent has its whole search range and correlation window inside.
  EXPECT_LE(window->x, u - half_width - (96 - 1) - 7);
  EXPECT_GE(window->x + window->width, u + half_width + 7);
  EXPECT_LE(window->y, v - half_height - 7);
  EXPECT_GE(window->y + window->height, v + half_height + 7);
  // ...and little more: a quarter of the image at 4 m, not all of it.
  EXPECT_LE(window->x, u - half_width - 102 + 0.0);
  EXPECT_GE(window->x, u - half_width - 102 - 2.0);
  EXPECT_LE(window->area(), 0.25 * 640 * 480);
}

TEST(TrackingWindow, ShrinksWithRangeDownToItsMinimum) {
  const cv::Matx34d p(550.0, 0.0, 319.5, 0.0, 0.0, 550.0, 239.5, 0.0, 0.0, 0.0, 1.0, 0.0);
  const TrackingWindowParams params;
  int last_area = 640 * 480;
  for (double z : {2.5, 3.5, 5.0, 7.0}) {
    const auto window = trackingWindow(p, Eigen::Vector3d(0.0, 0.0, z), cv::Size(640, 480), MatcherReach(), params);
    ASSERT_TRUE(window.has_value()) << z;
    EXPECT_LT(window->area(), last_area) << z;
    last_area = window->area();
  }
  // Very far: the minimum half size holds.
  const auto far = trackingWindow(p, Eigen::Vector3d(0.0, 0.0, 50.0), cv::Size(640, 480), MatcherReach(), params);
  ASSERT_TRUE(far.has_value());
  EXPECT_GE(far->height, 2 * kWindowMinHalfSizePx);
}

TEST(TrackingWindow, WholeImageWhenThePortCannotPlaceOne) {
  const cv::Matx34d p(550.0, 0.0, 319.5, 0.0, 0.0, 550.0, 239.5, 0.0, 0.0, 0.0, 1.0, 0.0);
  const TrackingWindowParams params;
  const cv::Size size(640, 480);
  EXPECT_FALSE(trackingWindow(p, Eigen::Vector3d(0.0, 0.0, -3.0), size, MatcherReach(), params));  // behind
  EXPECT_FALSE(trackingWindow(p, Eigen::Vector3d(4.0, 0.0, 3.0), size, MatcherReach(), params));   // out of view
  EXPECT_FALSE(trackingWindow(p, Eigen::Vector3d(0.0, 0.0, 1.0), size, MatcherReach(), params));   // too large
  EXPECT_FALSE(trackingWindow(p, Eigen::Vector3d(NAN, 0.0, 3.0), size, MatcherReach(), params));
}

TEST(TrackingWindow, PredictionFollowsTheVelocityForALimitedTime) {
  ASSERT_EQ(kMaxPredictionS, 0.5);  // the figures below
  const Eigen::Vector3d position(0.0, 0.0, 3.0), velocity(0.2, 0.0, -0.1);
  EXPECT_NEAR((predictPort(position, velocity, 0.25) - Eigen::Vector3d(0.05, 0.0, 2.975)).norm(), 0.0, 1e-12);
  EXPECT_NEAR((predictPort(position, velocity, 5.0) - Eigen::Vector3d(0.1, 0.0, 2.95)).norm(), 0.0, 1e-12);
  EXPECT_NEAR((predictPort(position, velocity, -1.0) - position).norm(), 0.0, 1e-12);
  EXPECT_NEAR((predictPort(position, Eigen::Vector3d(NAN, 0.0, 0.0), 0.2) - position).norm(), 0.0, 1e-12);
}

TEST(TrackingWindow, InvalidSettingsAreNamed) {
  TrackingWindowParams bad = configuredWindow();
  bad.half_width_m = 0.0;
  try {
    docking_settings::validateSettings(bad);
    FAIL() << "a window of no width accepted";
  } catch (const docking_settings::ConfigError& e) {
    EXPECT_EQ(e.key(), "half_width_m");  // the node's loader names it with its prefix, window_
  }
  EXPECT_NO_THROW(docking_settings::validateSettings(configuredWindow()));
}

TEST(TrackingWindow, RectifyingAWindowGivesTheWholeImagesPixels) {
  const PinholeCalibration c = testing::distortedWebcam();
  cv::Mat raw(c.size, CV_8UC1);
  cv::randu(raw, 0, 256);
  const WindowRectifier rectifier(c);
  cv::Mat whole, window;
  rectifier.rectify(raw, &whole);
  const cv::Rect area(101, 57, 233, 141);
  rectifier.rectifyWindow(raw, area, &window);
  ASSERT_EQ(window.size(), area.size());
  EXPECT_EQ(cv::norm(window, whole(area), cv::NORM_INF), 0.0);
  EXPECT_THROW(rectifier.rectifyWindow(raw, cv::Rect(600, 0, 80, 10), &window), std::invalid_argument);
}

// The target face-on and turned at 2.5-6 m: the window's estimate is the whole image's, to a few mm.
struct WindowCase {
  double x_m, z_m;
};
class WindowPipeline : public ::testing::TestWithParam<WindowCase> {};

TEST_P(WindowPipeline, FindsTheTargetWhereTheWholeImageDoes) {
  const WindowCase c = GetParam();
  const testing::FarStagePair pair = testing::farStagePair(testing::targetScene(c.x_m, 0.0, c.z_m, 12.0));
  const Detection whole = detectOn(pair, std::nullopt);
  ASSERT_TRUE(whole.found) << whole.reason;
  // The window placed from a prediction 0.15 m off to the side and 0.2 m off in range.
  const cv::Rect window = windowAround(pair, Eigen::Vector3d(c.x_m + 0.15, 0.0, c.z_m - 0.2));
  EXPECT_LT(window.area(), 0.5 * pair.left.total());
  const Detection windowed = detectOn(pair, window);
  ASSERT_TRUE(windowed.found) << windowed.reason;
  EXPECT_LT((windowed.position_m - whole.position_m).norm(), 0.01 + 0.002 * c.z_m)
      << "window " << windowed.position_m.transpose() << " vs whole " << whole.position_m.transpose();
  EXPECT_NEAR(windowed.position_m.z(), c.z_m, 0.02 * c.z_m);
}

INSTANTIATE_TEST_SUITE_P(Ranges, WindowPipeline,
                         ::testing::Values(WindowCase{0.0, 2.6}, WindowCase{0.4, 3.0}, WindowCase{-0.5, 4.0},
                                           WindowCase{0.3, 6.0}));

// The window's height (config/far_stereo.yaml window_half_height_m) leaves the face room above and below for
// a prediction off in height: both robots drive on the floor, so the port's height in the camera is
// nearly constant and 0.1 m (2 deg at 3 m) is more than a fused estimate's height error.
TEST(WindowPipeline, APredictionOffInHeightStillHoldsTheFace) {
  const double x_m = 0.2, z_m = 3.0;
  const testing::FarStagePair pair = testing::farStagePair(testing::targetScene(x_m, 0.0, z_m, 12.0));
  const Detection whole = detectOn(pair, std::nullopt);
  ASSERT_TRUE(whole.found) << whole.reason;
  for (const double dy : {-0.1, 0.1}) {
    const cv::Rect window = windowAround(pair, Eigen::Vector3d(x_m, dy, z_m));
    const Detection windowed = detectOn(pair, window);
    ASSERT_TRUE(windowed.found) << "height off by " << dy << " m: " << windowed.reason;
    // The tolerance of FindsTheTargetWhereTheWholeImageDoes (1.6 cm at 3 m).
    EXPECT_LT((windowed.position_m - whole.position_m).norm(), 0.01 + 0.002 * z_m) << "height off by " << dy << " m";
  }
}

// A box nearer than the target crossing the window's edge: a neighbour, looked behind. Told nothing of
// the window (its edges taken for the image's), the detector takes the box's cut part for the target (the
// matcher's own border leaves it a target-sized piece clear of the edge): what the ImageWindow prevents.
TEST(WindowPipeline, ABoxCrossingTheWindowsEdgeIsLookedBehind) {
  testing::SyntheticScene scene = testing::targetScene(0.0, 0.0, 4.0, 12.0);
  scene.rects.insert(scene.rects.begin(), testing::boxOnTheFloor(0.75, 3.4, 0.5, 0.3, 53));
  const testing::FarStagePair pair = testing::farStagePair(scene);
  const cv::Rect window = windowAround(pair, Eigen::Vector3d(0.0, 0.0, 4.0));
  const Detection untold = detectOn(pair, window, /*tell_detector_it_is_a_window=*/false);
  ASSERT_FALSE(untold.found && std::abs(untold.position_m.x()) < 0.1)
      << "the scene no longer puts the box across the window's edge: " << untold.reason;
  const Detection d = detectOn(pair, window);
  ASSERT_TRUE(d.found) << d.reason;
  EXPECT_NEAR(d.position_m.x(), 0.0, 0.05) << d.position_m.transpose();
  EXPECT_NEAR(d.position_m.z(), 4.0, 0.1) << d.position_m.transpose();
  EXPECT_GE(d.not_target_shaped_skipped + d.near_objects_skipped, 1);
}

// The window placed wrongly (the prediction 0.75 m off): the target crosses its edge and is reported not
// found, never found at a wrong place; nothing else in the window is taken for it.
TEST(WindowPipeline, AWindowThatCutsTheTargetReportsItNotFound) {
  const testing::FarStagePair pair = testing::farStagePair(testing::targetScene(0.0, 0.0, 3.0, 12.0));
  const cv::Rect window = windowAround(pair, Eigen::Vector3d(0.95, 0.0, 3.0));
  const Detection d = detectOn(pair, window);
  EXPECT_FALSE(d.found) << "found at " << d.position_m.transpose();
}

}  // namespace
}  // namespace disparity
}  // namespace docking_perception
