// The far-range pipeline on rendered stereo pairs: the block matcher with the settings of
// config/stereo_image_proc.yaml (what perception.launch runs), then the detector with
// config/disparity_detector.yaml. Known truth: the port centre of the rendered target.
#include <cmath>
#include <string>

#include <gtest/gtest.h>

#include "docking_perception/disparity/disparity_detector.h"
#include "synthetic_stereo.h"

namespace docking_perception {
namespace disparity {
namespace {

const std::string kConfigDir = DISPARITY_CONFIG_DIR;

struct PipelineResult {
  Detection detection;
  double stereo_limit_m = 0.0;  // Z^2 * 0.25 px / (f B): the yardstick
};

PipelineResult runPipeline(double x, double y, double z) {
  const auto settings = testing::loadMatcherSettings(kConfigDir + "/stereo_image_proc.yaml");
  const auto params = testing::loadDetectorParams(kConfigDir + "/disparity_detector.yaml");
  const testing::SyntheticScene scene = testing::targetScene(x, y, z, 12.0);
  cv::Mat left, right;
  testing::renderStereoPair(scene, &left, &right);
  auto matcher = testing::createMatcher(settings);
  const cv::Mat disparity = testing::computeDisparity(*matcher, left, right);

  const StereoGeometry geometry = testing::geometryOf(scene);
  const cv::Rect valid = testing::matcherValidRegion(settings, disparity.size());

  PipelineResult result;
  result.detection = DisparityDetector(params).detect(
      disparity, geometry, settings.min_disparity, testing::maxDisparity(settings), valid);
  result.stereo_limit_m = z * z * 0.25 / (geometry.focal_px * geometry.baseline_m);
  return result;
}

class FarRangePipeline : public ::testing::TestWithParam<std::tuple<double, double>> {};

TEST_P(FarRangePipeline, PositionWithinTwiceTheStereoLimit) {
  const double z = std::get<0>(GetParam());
  const double x = std::get<1>(GetParam());
  const double y = 0.0;  // the port is at camera height on the test bed
  const PipelineResult result = runPipeline(x, y, z);
  const Detection& d = result.detection;
  ASSERT_TRUE(d.found) << "z " << z << " x " << x << ": " << d.reason;
  const double tolerance = 2.0 * result.stereo_limit_m;
  EXPECT_NEAR(d.position_m.z(), z, tolerance);
  // Lateral: the face centre in the image, a few cm at most.
  EXPECT_NEAR(d.position_m.x(), x, 0.03 + 0.01 * z);
  EXPECT_NEAR(d.position_m.y(), y, 0.03 + 0.01 * z);
  // The covariance is consistent with the error it claims (within 4 sigma).
  EXPECT_LT(std::abs(d.position_m.z() - z), 4.0 * std::sqrt(d.covariance_m2(2, 2)) + 0.01 * z);
}

INSTANTIATE_TEST_SUITE_P(OnAndOffAxis, FarRangePipeline,
                         ::testing::Values(std::make_tuple(2.0, 0.0), std::make_tuple(3.0, 0.0),
                                           std::make_tuple(3.0, 0.6), std::make_tuple(4.0, -0.5),
                                           std::make_tuple(6.0, 0.0), std::make_tuple(6.0, 1.0)));

TEST(FarRangePipeline, ConfigFilesAreComplete) {
  EXPECT_NO_THROW(testing::loadMatcherSettings(kConfigDir + "/stereo_image_proc.yaml"));
  const auto params = testing::loadDetectorParams(kConfigDir + "/disparity_detector.yaml");
  EXPECT_TRUE(validateParams(params).empty());
  EXPECT_THROW(testing::loadMatcherSettings(kConfigDir + "/no_such_file.yaml"), std::runtime_error);
}

}  // namespace
}  // namespace disparity
}  // namespace docking_perception
