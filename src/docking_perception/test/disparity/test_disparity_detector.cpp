// The detector on synthetic disparity images with known answers (no ROS, no matcher).
#include <cmath>
#include <limits>
#include <random>
#include <stdexcept>

#include <Eigen/Eigenvalues>
#include <gtest/gtest.h>

#include "docking_perception/disparity/disparity_detector.h"
#include "painted_disparity.h"

#include <docking_settings/config_error.h>

namespace docking_perception {
namespace disparity {
namespace {

using test::disparityAt;
using test::ourGeometry;
using test::paintRect;
using test::detectorWith;
using test::shippedDetector;
using test::shippedParams;
using test::shippedShape;
using test::shippedRig;

cv::Mat invalidImage() { return cv::Mat(480, 640, CV_32FC1, cv::Scalar(-1.0f)); }

// The projected centre of the painted rectangle, in pixels (for centre checks independent of depth).
cv::Point2d projected(double x, double y, double z) {
  const StereoGeometry g = ourGeometry();
  return {g.cx_px + x * g.focal_px / z, g.cy_px + y * g.focal_px / z};
}

TEST(DisparityDetector, PlaneAtKnownDepthIsFoundAtItsPosition) {
  cv::Mat disparity = invalidImage();
  paintRect(&disparity, 0.20, -0.05, 3.0, 0.30, 0.24);
  const DisparityDetector detector = shippedDetector();
  const Detection result = detector.detect(disparity, ourGeometry());
  ASSERT_TRUE(result.found) << result.reason;
  EXPECT_EQ(result.outcome, StageOutcome(PlausibilityOutcome::kPassed));
  EXPECT_TRUE(result.reason.empty());
  EXPECT_NEAR(result.disparity_px, disparityAt(3.0), 1e-4);
  EXPECT_NEAR(result.position_m.z(), 3.0, 1e-3);
  // Pixel quantisation of the painted edges: well under a centimetre at 3 m.
  EXPECT_NEAR(result.position_m.x(), 0.20, 0.01);
  EXPECT_NEAR(result.position_m.y(), -0.05, 0.01);
  EXPECT_NEAR(result.range_m, std::sqrt(0.2 * 0.2 + 0.05 * 0.05 + 9.0), 0.01);
  EXPECT_GT(result.blob_pixels, 2000);
  ASSERT_FALSE(result.mask.empty());
  EXPECT_EQ(cv::countNonZero(result.mask), result.blob_pixels);
  EXPECT_GE(result.contour.size(), 4u);
}

TEST(DisparityDetector, NearerOfTwoObjectsWins) {
  cv::Mat disparity = invalidImage();
  paintRect(&disparity, -0.6, 0.0, 4.0, 0.6, 0.5);   // bigger, farther
  paintRect(&disparity, 0.4, -0.02, 2.5, 0.30, 0.24);  // smaller, nearer: the target
  const Detection result = shippedDetector().detect(disparity, ourGeometry());
  ASSERT_TRUE(result.found) << result.reason;
  EXPECT_NEAR(result.position_m.z(), 2.5, 0.01);
  EXPECT_NEAR(result.position_m.x(), 0.4, 0.01);
  EXPECT_NEAR(result.position_m.y(), -0.02, 0.01);
}

TEST(DisparityDetector, NoisyPlaneWithSpikesIsRecovered) {
  // Background wall at 10 m and a target at 3 m, both with 0.3 px Gaussian noise, 10% dropouts and
  // 0.5% isolated spikes at 60..90 px: the single largest disparity would be a spike.
  cv::Mat disparity(480, 640, CV_32FC1, cv::Scalar(disparityAt(10.0)));
  paintRect(&disparity, -0.1, 0.0, 3.0, 0.30, 0.24);
  std::mt19937 rng(42);
  std::normal_distribution<float> noise(0.0f, 0.3f);
  std::uniform_real_distribution<float> unit(0.0f, 1.0f);
  for (int v = 0; v < disparity.rows; ++v) {
    for (int u = 0; u < disparity.cols; ++u) {
      float& d = disparity.at<float>(v, u);
      const float draw = unit(rng);
      if (draw < 0.10f) {
        d = std::numeric_limits<float>::quiet_NaN();
      } else if (draw < 0.105f) {
        d = 60.0f + 30.0f * unit(rng);
      } else {
        d += noise(rng);
      }
    }
  }
  const Detection result = shippedDetector().detect(disparity, ourGeometry());
  ASSERT_TRUE(result.found) << result.reason;
  EXPECT_LT(result.closest_disparity_px, 25.0) << "a spike was taken as the closest object";
  EXPECT_NEAR(result.position_m.z(), 3.0, 0.03 * 3.0);
  EXPECT_NEAR(result.position_m.x(), -0.1, 0.02);
  EXPECT_NEAR(result.position_m.y(), 0.0, 0.02);
}

TEST(DisparityDetector, EmptyImageIsRejectedWithReason) {
  const DisparityDetector detector = shippedDetector();
  const Detection empty = detector.detect(cv::Mat(), ourGeometry());
  EXPECT_FALSE(empty.found);
  EXPECT_EQ(empty.outcome, StageOutcome(InputOutcome::kEmptyImage));
  EXPECT_NE(empty.reason.find("empty"), std::string::npos) << empty.reason;
}

TEST(DisparityDetector, AllInvalidImageIsRejectedWithReason) {
  const DisparityDetector detector = shippedDetector();
  cv::Mat nan_image(480, 640, CV_32FC1, cv::Scalar(std::numeric_limits<float>::quiet_NaN()));
  for (const cv::Mat& image : {invalidImage(), nan_image}) {
    const Detection result = detector.detect(image, ourGeometry());
    EXPECT_FALSE(result.found);
    EXPECT_EQ(result.outcome, StageOutcome(ValidDisparityOutcome::kTooFewValid));
    EXPECT_EQ(result.valid_pixels, 0);
    EXPECT_NE(result.reason.find("valid disparity"), std::string::npos) << result.reason;
  }
}

TEST(DisparityDetector, WrongImageTypeAndGeometryAreRejectedWithReason) {
  const DisparityDetector detector = shippedDetector();
  const Detection wrong_type = detector.detect(cv::Mat(480, 640, CV_16SC1, cv::Scalar(100)),
                                               ourGeometry());
  EXPECT_EQ(wrong_type.outcome, StageOutcome(InputOutcome::kBadEncoding));
  EXPECT_NE(wrong_type.reason.find("32-bit float"), std::string::npos) << wrong_type.reason;

  cv::Mat disparity = invalidImage();
  paintRect(&disparity, 0.0, 0.0, 3.0, 0.30, 0.24);
  StereoGeometry no_baseline = ourGeometry();
  no_baseline.baseline_m = 0.0;
  const Detection bad_geometry = detector.detect(disparity, no_baseline);
  EXPECT_EQ(bad_geometry.outcome, StageOutcome(InputOutcome::kBadGeometry));
  EXPECT_NE(bad_geometry.reason.find("baseline"), std::string::npos) << bad_geometry.reason;
}

TEST(DisparityDetector, BlobOnTheImageBorderIsRejected) {
  cv::Mat disparity = invalidImage();
  // Cut by the right image edge: the centre of what is visible is not the target's centre.
  disparity(cv::Rect(600, 200, 40, 60)).setTo(cv::Scalar(disparityAt(3.0)));
  const Detection result = shippedDetector().detect(disparity, ourGeometry());
  EXPECT_FALSE(result.found);
  EXPECT_EQ(result.outcome, StageOutcome(PlausibilityOutcome::kBlobTouchesBorder));
  EXPECT_NE(result.reason.find("right"), std::string::npos) << result.reason;
  EXPECT_FALSE(result.mask.empty()) << "a rejected blob is still returned for the debug image";

  DetectorParams keep_cut = shippedParams();
  keep_cut.reject_cut_blobs = false;  // the ablation's switch (scripts/ablate/rules): then it is reported
  EXPECT_TRUE(detectorWith(keep_cut).detect(disparity, ourGeometry()).found);
}

TEST(DisparityDetector, BlobOnTheBlindLeftBandIsRejected) {
  // The matcher cannot match the left columns (the search range): a blob starting right at that
  // band's edge is cut by it, even though it is far from the image's own left edge.
  cv::Mat disparity = invalidImage();
  disparity(cv::Rect(110, 200, 50, 40)).setTo(cv::Scalar(disparityAt(3.0)));
  const DisparityDetector detector = shippedDetector();
  const Detection in_full_image = detector.detect(disparity, ourGeometry());
  EXPECT_TRUE(in_full_image.found) << in_full_image.reason;
  const Detection with_band =
      detector.detect(disparity, ourGeometry(), 0.0, 95.0, cv::Rect(109, 0, 531, 480));
  EXPECT_EQ(with_band.outcome, StageOutcome(PlausibilityOutcome::kBlobTouchesBorder));
  EXPECT_NE(with_band.reason.find("left"), std::string::npos) << with_band.reason;
}

TEST(DisparityDetector, TooSmallBlobIsRejected) {
  cv::Mat disparity = invalidImage();
  disparity(cv::Rect(300, 200, 10, 10)).setTo(cv::Scalar(disparityAt(3.0)));
  DetectorParams params = shippedParams();
  params.closest_min_pixels = 20;  // the 100-pixel square is "the closest object"...
  params.min_blob_area_px = 150;   // ...but too small to be the target
  const Detection result = detectorWith(params).detect(disparity, ourGeometry());
  EXPECT_FALSE(result.found);
  EXPECT_EQ(result.outcome, StageOutcome(BandSearchOutcome::kAllBlobsTooSmall));
  EXPECT_NE(result.reason.find("too small"), std::string::npos) << result.reason;
  EXPECT_FALSE(result.contour.empty()) << "the rejected blob is kept for the debug image";
}

TEST(DisparityDetector, SmallNearObjectIsLookedBehind) {
  // A 20x20 px patch at 1.2 m (say, a mismatch at an occlusion edge) is nearer than the target and
  // bigger than closest_min_pixels, but smaller than any target: the target behind it is found.
  cv::Mat disparity = invalidImage();
  paintRect(&disparity, 0.1, 0.0, 3.0, 0.30, 0.24);
  disparity(cv::Rect(150, 120, 20, 20)).setTo(cv::Scalar(disparityAt(1.2)));
  const Detection result = shippedDetector().detect(disparity, ourGeometry());
  ASSERT_TRUE(result.found) << result.reason;
  EXPECT_EQ(result.near_objects_skipped, 1);
  EXPECT_NEAR(result.position_m.z(), 3.0, 0.01);
  EXPECT_NEAR(result.position_m.x(), 0.1, 0.01);
}

TEST(DisparityDetector, ThinNearStripIsLookedBehind) {
  // An 8 px wide, 80 px tall strip at 0.86 m (600 px, more than min_blob_area_px): what block
  // matching produces in the occlusion band at the target's left edge. Too thin to be a target.
  cv::Mat disparity = invalidImage();
  paintRect(&disparity, 0.0, 0.0, 2.0, 0.30, 0.24);
  disparity(cv::Rect(230, 200, 8, 80)).setTo(cv::Scalar(64.0));
  const Detection result = shippedDetector().detect(disparity, ourGeometry());
  ASSERT_TRUE(result.found) << result.reason;
  EXPECT_EQ(result.near_objects_skipped, 1);
  EXPECT_NEAR(result.position_m.z(), 2.0, 0.01);

  DetectorParams no_thickness_check = shippedParams();
  no_thickness_check.min_blob_thickness_px = 0.0;
  no_thickness_check.shape_check_enabled = false;  // it refuses the strip too (its width): the thickness alone
  const Detection fooled = detectorWith(no_thickness_check).detect(disparity, ourGeometry());
  EXPECT_LT(fooled.position_m.z(), 1.0) << "without the check the strip is taken for the target";
}

TEST(DisparityDetector, TinyNearSpeckDoesNotHideTheTarget) {
  // Fewer near pixels than closest_min_pixels: the speck is not "the closest object".
  cv::Mat disparity = invalidImage();
  paintRect(&disparity, 0.0, 0.0, 3.0, 0.30, 0.24);
  disparity(cv::Rect(100 + 150, 100, 8, 8)).setTo(cv::Scalar(disparityAt(1.0)));
  const Detection result = shippedDetector().detect(disparity, ourGeometry());
  ASSERT_TRUE(result.found) << result.reason;
  EXPECT_NEAR(result.position_m.z(), 3.0, 0.01);
}

TEST(DisparityDetector, DisparityOutsideThePlausibleRangeIsRejected) {
  cv::Mat disparity = invalidImage();
  paintRect(&disparity, 0.0, 0.0, 0.55, 0.30, 0.24);  // the face at 0.55 m: 100 px > max_disparity_px 92
  const Detection result = shippedDetector().detect(disparity, ourGeometry());
  EXPECT_FALSE(result.found);
  EXPECT_EQ(result.outcome, StageOutcome(PlausibilityOutcome::kDisparityOutOfRange));
  EXPECT_NEAR(result.disparity_px, disparityAt(0.55), 1e-3);
}

TEST(DisparityDetector, FloorIsIgnoredByTheHeightCut) {
  // A floor 0.25 m below the cameras (the chaser's camera height) is nearer than the target in the
  // lower rows and touches the bottom border.
  cv::Mat disparity = invalidImage();
  const StereoGeometry g = ourGeometry();
  for (int v = 0; v < disparity.rows; ++v) {
    if (v <= g.cy_px + 1) continue;
    disparity.row(v).setTo(cv::Scalar((v - g.cy_px) * g.baseline_m / 0.25));
  }
  paintRect(&disparity, 0.1, 0.0, 3.0, 0.30, 0.24);

  DetectorParams params = shippedParams();
  const Detection with_cut = detectorWith(params).detect(disparity, g);
  ASSERT_TRUE(with_cut.found) << with_cut.reason;
  EXPECT_NEAR(with_cut.position_m.z(), 3.0, 0.01);
  EXPECT_NEAR(with_cut.position_m.x(), 0.1, 0.01);

  params.level_floor = false;
  const Detection without_cut = detectorWith(params).detect(disparity, g);
  EXPECT_FALSE(without_cut.found) << "without the cut the floor is the closest object";
}

TEST(DisparityDetector, CentreIsTheFaceNotTheWholeBlob) {
  // The face at 3.00 m with a solar panel 0.15 m behind it on one side only: the blob holds both,
  // the centre and depth must be the face's.
  cv::Mat disparity = invalidImage();
  paintRect(&disparity, 0.30, 0.0, 3.15, 0.30, 0.16);  // panel to the right of the box
  paintRect(&disparity, 0.0, 0.0, 3.0, 0.30, 0.24);    // face
  // The nearest layer's centroid, which the shipped footprint fit replaces (test_footprint_fit.cpp); the
  // ablation runs it when the fit is off.
  DetectorParams nearest_layer = shippedParams();
  nearest_layer.footprint_fit_enabled = false;
  const Detection result = detectorWith(nearest_layer).detect(disparity, ourGeometry());
  ASSERT_TRUE(result.found) << result.reason;
  EXPECT_GT(result.blob_pixels, result.face_pixels) << "the panel belongs to the blob";
  const cv::Point2d face_centre = projected(0.0, 0.0, 3.0);
  EXPECT_NEAR(result.centre_px.x, face_centre.x, 1.0);
  EXPECT_NEAR(result.position_m.x(), 0.0, 0.01);
  EXPECT_NEAR(result.position_m.z(), 3.0, 0.01);
}

TEST(Reproject, DepthSigmaGrowsAsRangeSquaredAndLateralAsRange) {
  const StereoGeometry g = ourGeometry();
  Eigen::Vector3d near_position, far_position;
  Eigen::Matrix3d near_cov, far_cov;
  const cv::Point2d on_axis(g.cx_px, g.cy_px);
  reproject(g, on_axis, disparityAt(2.0), 1.0, 0.25, &near_position, &near_cov);
  reproject(g, on_axis, disparityAt(4.0), 1.0, 0.25, &far_position, &far_cov);
  EXPECT_NEAR(near_position.z(), 2.0, 1e-9);
  EXPECT_NEAR(far_position.z(), 4.0, 1e-9);
  // sigma_Z = Z^2 sigma_d / (f B)
  EXPECT_NEAR(std::sqrt(near_cov(2, 2)), 4.0 * 0.25 / 55.0, 1e-9);
  EXPECT_NEAR(std::sqrt(far_cov(2, 2)) / std::sqrt(near_cov(2, 2)), 4.0, 1e-9);
  // Lateral from pixel noise: sigma_X = Z sigma_u / f on the axis.
  EXPECT_NEAR(std::sqrt(far_cov(0, 0)), 4.0 * 1.0 / 550.0, 1e-9);
  EXPECT_NEAR(std::sqrt(far_cov(0, 0)) / std::sqrt(near_cov(0, 0)), 2.0, 1e-9);
}

TEST(Reproject, DepthErrorLiesAlongTheLineOfSight) {
  // Off-axis, the largest error axis is the ray to the point, not the optical axis.
  const StereoGeometry g = ourGeometry();
  Eigen::Vector3d position;
  Eigen::Matrix3d cov;
  reproject(g, cv::Point2d(g.cx_px + 200.0, g.cy_px - 80.0), disparityAt(5.0), 1.0, 0.25, &position,
            &cov);
  EXPECT_TRUE(cov.isApprox(cov.transpose()));
  Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> solver(cov);
  ASSERT_EQ(solver.info(), Eigen::Success);
  EXPECT_GT(solver.eigenvalues().minCoeff(), 0.0);
  const Eigen::Vector3d major_axis = solver.eigenvectors().col(2);
  const double cos_angle = std::abs(major_axis.dot(position.normalized()));
  EXPECT_GT(cos_angle, std::cos(0.5 * M_PI / 180.0));
  EXPECT_LT(std::abs(major_axis.dot(Eigen::Vector3d::UnitZ())), 0.96) << "not the optical axis";
}

TEST(DisparityDetector, DetectedCovarianceGrowsAsRangeSquared) {
  // The propagated stereo noise alone: the port offset term is the same at every range.
  DetectorParams params = shippedParams();
  params.port_offset_sigma_m = 0.0;
  const DisparityDetector detector = detectorWith(params);
  cv::Mat near_image = invalidImage(), far_image = invalidImage();
  paintRect(&near_image, 0.0, 0.0, 2.0, 0.30, 0.24);
  paintRect(&far_image, 0.0, 0.0, 4.0, 0.30, 0.24);
  const Detection near_result = detector.detect(near_image, ourGeometry());
  const Detection far_result = detector.detect(far_image, ourGeometry());
  ASSERT_TRUE(near_result.found && far_result.found);
  EXPECT_NEAR(std::sqrt(far_result.covariance_m2(2, 2) / near_result.covariance_m2(2, 2)), 4.0, 0.05);
}

// The key named in a refused configuration (the node's loader prefixes nothing: the detector's keys are
// top-level).
std::string refusedKey(const DetectorParams& params) {
  try {
    validate(params, shippedShape(), shippedRig());
  } catch (const docking_settings::ConfigError& e) {
    return e.key();
  }
  return "";
}

TEST(DetectorParams, InvalidSettingsAreNamedAndNotApplied) {
  EXPECT_EQ(refusedKey(shippedParams()), "");
  DetectorParams bad = shippedParams();
  bad.median_kernel_px = 4;  // inside its range, but not a kernel OpenCV's float median has
  EXPECT_EQ(refusedKey(bad), "median_kernel_px");
  bad = shippedParams();
  bad.max_disparity_px = 2.0;  // below min_disparity_px 4
  EXPECT_EQ(refusedKey(bad), "max_disparity_px");
  bad = shippedParams();
  bad.min_blob_area_px = 0;  // outside its declared range
  EXPECT_EQ(refusedKey(bad), "min_blob_area_px");

  DisparityDetector detector = shippedDetector();
  EXPECT_THROW(detector.setParams(bad), std::invalid_argument);
  EXPECT_EQ(detector.params().min_blob_area_px, shippedParams().min_blob_area_px);
}

TEST(DebugImage, ShowsTheBlobInTheOutcomeColour) {
  cv::Mat disparity = invalidImage();
  paintRect(&disparity, 0.0, 0.0, 3.0, 0.30, 0.24);
  const Detection found = shippedDetector().detect(disparity, ourGeometry());
  const cv::Mat image = renderDebugImage(disparity, found, 100.0);
  ASSERT_EQ(image.type(), CV_8UC3);
  ASSERT_EQ(image.size(), disparity.size());
  // Inside the blob, away from the contour and centre marks: green dominates.
  const cv::Vec3b inside = image.at<cv::Vec3b>(cv::Point(found.bounding_box.x + 5,
                                                         found.bounding_box.y + 5));
  EXPECT_GT(inside[1], inside[2]);
  EXPECT_GT(inside[1], inside[0]);
  // Outside, the invalid disparity is black.
  EXPECT_EQ(image.at<cv::Vec3b>(cv::Point(50, 400)), cv::Vec3b(0, 0, 0));
}

}  // namespace
}  // namespace disparity
}  // namespace docking_perception
