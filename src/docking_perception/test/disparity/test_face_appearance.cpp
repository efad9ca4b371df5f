// The appearance check of a far blob (face_appearance.h, issue 11): the shipped face print, drawn with a
// homography into a textured scene at 2-6 m, blurred and noisy, is found where the detector puts the port;
// a box of the mockup's size with another texture is not; glare and darkness are not judged.
#include <cmath>
#include <random>
#include <string>

#include <gtest/gtest.h>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

#include "docking_perception/disparity/disparity_detector.h"
#include "docking_perception/disparity/face_appearance.h"
#include "painted_disparity.h"

#include <docking_settings/config_error.h>

namespace docking_perception {
namespace disparity {
namespace {

const std::string kConfigDir = DISPARITY_CONFIG_DIR;
constexpr double kFaceWidthM = 0.30, kFaceHeightM = 0.24;  // config/target.yaml

StereoGeometry ourCamera() { return test::ourGeometry(); }

cv::Mat shippedPrint() {
  const cv::Mat print = cv::imread(kConfigDir + "/textures/target_face.png", cv::IMREAD_GRAYSCALE);
  if (print.empty()) throw std::runtime_error("cannot read the shipped face print");
  return print;
}

// Random grey cells `cell_px` wide: a wall, a box's print, a busy room.
cv::Mat cellTexture(cv::Size size, int cell_px, unsigned seed, int low = 40, int high = 220) {
  std::mt19937 random(seed);
  std::uniform_int_distribution<int> grey(low, high);
  cv::Mat cells((size.height + cell_px - 1) / cell_px, (size.width + cell_px - 1) / cell_px, CV_8UC1);
  for (int r = 0; r < cells.rows; ++r)
    for (int c = 0; c < cells.cols; ++c) cells.at<unsigned char>(r, c) = static_cast<unsigned char>(grey(random));
  cv::Mat texture;
  cv::resize(cells, texture, cv::Size(cells.cols * cell_px, cells.rows * cell_px), 0, 0, cv::INTER_NEAREST);
  return texture(cv::Rect(0, 0, size.width, size.height)).clone();
}

// Draws `picture` as a face of the mockup's size, its centre at `port` (left optical frame), turned by
// `yaw_rad` about the vertical, into `image`.
void drawFace(const cv::Mat& picture, const Eigen::Vector3d& port, double yaw_rad, cv::Mat* image) {
  const StereoGeometry g = ourCamera();
  const Eigen::Vector3d along(std::cos(yaw_rad), 0.0, std::sin(yaw_rad));  // picture columns
  const Eigen::Vector3d down(0.0, 1.0, 0.0);                                // picture rows
  std::vector<cv::Point2f> from, to;
  const double corners[4][2] = {{-0.5, -0.5}, {0.5, -0.5}, {0.5, 0.5}, {-0.5, 0.5}};
  for (const auto& corner : corners) {
    const Eigen::Vector3d p = port + corner[0] * kFaceWidthM * along + corner[1] * kFaceHeightM * down;
    to.emplace_back(static_cast<float>(g.cx_px + g.focal_px * p.x() / p.z()),
                    static_cast<float>(g.cy_px + g.focal_px * p.y() / p.z()));
    from.emplace_back(static_cast<float>((corner[0] + 0.5) * picture.cols), static_cast<float>((corner[1] + 0.5) * picture.rows));
  }
  cv::warpPerspective(picture, *image, cv::getPerspectiveTransform(from, to), image->size(), cv::INTER_AREA,
                      cv::BORDER_TRANSPARENT);
}

// A camera's view: textured room, the face, defocus and sensor noise.
cv::Mat scene(const cv::Mat& face_picture, const Eigen::Vector3d& port, double yaw_rad, double blur_sigma_px,
              double noise_dn, unsigned seed = 3) {
  cv::Mat image = cellTexture(cv::Size(640, 480), 23, seed, 90, 170);
  drawFace(face_picture, port, yaw_rad, &image);
  if (blur_sigma_px > 0.0) cv::GaussianBlur(image, image, cv::Size(), blur_sigma_px);
  cv::Mat noise(image.size(), CV_16SC1);
  cv::randn(noise, 0.0, noise_dn);
  cv::Mat noisy;
  image.convertTo(noisy, CV_16SC1);
  noisy += noise;
  noisy.convertTo(image, CV_8UC1);
  return image;
}

// The shipped appearance settings (config/disparity_detector.yaml over the declared defaults).
FaceAppearanceParams shippedAppearance() { return test::shippedParams().appearance; }

// A detection the detector found at `position_m`, with `covariance_m2` (default: none).
Detection foundAt(const Eigen::Vector3d& position_m, const Eigen::Matrix3d& covariance_m2 = Eigen::Matrix3d::Zero()) {
  Detection detection;
  detection.found = true;
  detection.outcome = PlausibilityOutcome::kPassed;
  detection.position_m = position_m;
  detection.covariance_m2 = covariance_m2;
  return detection;
}

TEST(FaceAppearance, ThePrintIsFoundFromTwoToSixMetresTurnedAndWithThePortOffByTheDetectorsError) {
  const cv::Mat print = shippedPrint();
  const FaceAppearanceCheck check(print, kFaceWidthM, kFaceHeightM);
  for (double z : {2.0, 3.0, 4.5, 6.0}) {
    for (double yaw_deg : {0.0, 35.0, -50.0}) {
      const Eigen::Vector3d port(0.3, 0.02, z);
      const cv::Mat image = scene(print, port, yaw_deg * M_PI / 180.0, 1.0, 4.0);
      // The detector's port: up to ~0.1 m beside the truth at 6 m.
      const Eigen::Vector3d detected = port + Eigen::Vector3d(0.08, -0.03, 0.05);
      const AppearanceResult result = check.check(image, ourCamera(), detected, shippedAppearance());
      EXPECT_EQ(result.verdict, AppearanceVerdict::kLooksLikeTarget)
          << "z " << z << " yaw " << yaw_deg << ": " << result.reason;
      // Measured 0.56 (6 m, turned 50 deg) to 0.81 (2 m); boxes 0.22-0.38 (below).
      EXPECT_GE(result.score, shippedAppearance().min_score + 0.05) << "z " << z << " yaw " << yaw_deg;
      // The match is on the face, not beside it.
      const double truth_u = 319.5 + 550.0 * port.x() / z;
      EXPECT_NEAR(result.matched_centre_px.x, truth_u, 0.05 * 550.0 / z + 2.0) << "z " << z << " yaw " << yaw_deg;
    }
  }
}

TEST(FaceAppearance, AMatchedPrintMovesThePortAcrossTheLineOfSightToThePrintsCentre) {
  const cv::Mat print = shippedPrint();
  const FaceAppearanceCheck check(print, kFaceWidthM, kFaceHeightM);
  for (double z : {2.0, 3.0, 4.5, 6.0}) {
    for (double yaw_deg : {0.0, 35.0, -50.0}) {
      const Eigen::Vector3d port(-0.4, 0.01, z);
      const cv::Mat image = scene(print, port, yaw_deg * M_PI / 180.0, 1.0, 4.0);
      // A turned target's footprint fit: the port 0.2 m aside (campaign seed 7515: up to 0.23 m at 2.7 m).
      Detection detection = foundAt(port + Eigen::Vector3d(0.2, -0.04, 0.03));
      confirmByAppearance(check, image, cv::Mat(), ourCamera(), shippedAppearance(), &detection);
      ASSERT_TRUE(detection.found) << detection.reason;
      // Within ~1 px of the working scale (the face reduced to 24 px: 1.2 cm at 2 m, 1.1 cm at 6 m).
      EXPECT_NEAR(detection.position_m.x(), port.x(), 0.025) << "z " << z << " yaw " << yaw_deg;
      EXPECT_NEAR(detection.position_m.y(), port.y(), 0.025) << "z " << z << " yaw " << yaw_deg;
      EXPECT_DOUBLE_EQ(detection.position_m.z(), z + 0.03);  // the depth stays the disparity's
      EXPECT_NEAR(detection.range_m, detection.position_m.norm(), 1e-9);
    }
  }
  // Switched off: the check judges, the port stays.
  FaceAppearanceParams keep = shippedAppearance();
  keep.refine_port = false;
  const Eigen::Vector3d port(0.2, 0.0, 3.0);
  Detection detection = foundAt(port + Eigen::Vector3d(0.1, 0.0, 0.0));
  confirmByAppearance(check, scene(print, port, 0.0, 1.0, 4.0), cv::Mat(), ourCamera(), keep, &detection);
  EXPECT_TRUE(detection.found);
  EXPECT_DOUBLE_EQ(detection.position_m.x(), 0.3);
}

TEST(FaceAppearance, AMatchedPrintTakesThePortsDepthFromTheFacesOwnDisparity) {
  const cv::Mat print = shippedPrint();
  const FaceAppearanceCheck check(print, kFaceWidthM, kFaceHeightM);
  const Eigen::Vector3d port(0.3, 0.0, 2.2);
  const cv::Mat image = scene(print, port, 0.0, 1.0, 4.0);
  // The face at its depth, a wall 1 m behind it around.
  cv::Mat disparity(image.size(), CV_32FC1, cv::Scalar(static_cast<float>(test::disparityAt(3.2))));
  const double u = 319.5 + 550.0 * port.x() / port.z(), half_w = 550.0 * kFaceWidthM / port.z() / 2.0;
  const double half_h = 550.0 * kFaceHeightM / port.z() / 2.0;
  disparity(cv::Rect(cv::Point(static_cast<int>(u - half_w), static_cast<int>(239.5 - half_h)),
                     cv::Point(static_cast<int>(u + half_w), static_cast<int>(239.5 + half_h))))
      .setTo(static_cast<float>(test::disparityAt(port.z())));
  // The footprint fit's swing at 2.2 m, with the detector's depth sigma there.
  Detection detection = foundAt(port + Eigen::Vector3d(0.1, 0.0, 0.12), Eigen::Matrix3d::Identity() * 0.046 * 0.046);
  confirmByAppearance(check, image, disparity, ourCamera(), shippedAppearance(), &detection);
  ASSERT_TRUE(detection.found) << detection.reason;
  EXPECT_NEAR(detection.position_m.z(), port.z(), 0.005);
  EXPECT_NEAR(detection.position_m.x(), port.x(), 0.025);
  EXPECT_NEAR(detection.disparity_px, test::disparityAt(port.z()), 1e-4);

  // Too few valid disparities on the face: its depth is kept.
  cv::Mat holes(image.size(), CV_32FC1, cv::Scalar(-1.0f));
  Detection kept = foundAt(port + Eigen::Vector3d(0.0, 0.0, 0.12), detection.covariance_m2);
  confirmByAppearance(check, image, holes, ourCamera(), shippedAppearance(), &kept);
  ASSERT_TRUE(kept.found);
  EXPECT_DOUBLE_EQ(kept.position_m.z(), port.z() + 0.12);

  // Agreeing within twice the depth sigma: the detection's depth stands (the steadier far away).
  Detection agreeing = foundAt(port + Eigen::Vector3d(0.0, 0.0, 0.05), detection.covariance_m2);
  confirmByAppearance(check, image, disparity, ourCamera(), shippedAppearance(), &agreeing);
  ASSERT_TRUE(agreeing.found);
  EXPECT_DOUBLE_EQ(agreeing.position_m.z(), port.z() + 0.05);
}

TEST(FaceAppearance, GainAndOffsetDoNotMatter) {
  const cv::Mat print = shippedPrint();
  const FaceAppearanceCheck check(print, kFaceWidthM, kFaceHeightM);
  const Eigen::Vector3d port(0.0, 0.0, 4.0);
  cv::Mat dim;
  scene(print, port, 0.0, 1.5, 2.0).convertTo(dim, CV_8UC1, 0.45, 20.0);
  const AppearanceResult result = check.check(dim, ourCamera(), port, shippedAppearance());
  EXPECT_EQ(result.verdict, AppearanceVerdict::kLooksLikeTarget) << result.reason;
}

TEST(FaceAppearance, ABoxOfTheMockupsSizeWithAnotherTextureIsNotTheTarget) {
  const cv::Mat print = shippedPrint();
  const FaceAppearanceCheck check(print, kFaceWidthM, kFaceHeightM);
  int cases = 0;
  for (double z : {2.5, 4.0, 6.0}) {
    for (int cell_px : {12, 30, 60}) {
      for (unsigned seed : {1u, 2u}) {
        const cv::Mat box_print = cellTexture(print.size(), cell_px, seed);
        const Eigen::Vector3d port(-0.2, 0.0, z);
        const cv::Mat image = scene(box_print, port, 0.2, 1.0, 4.0, seed + 10);
        const AppearanceResult result = check.check(image, ourCamera(), port, shippedAppearance());
        EXPECT_EQ(result.verdict, AppearanceVerdict::kNotTheTarget)
            << "z " << z << " cells " << cell_px << " seed " << seed << ": " << result.reason;
        EXPECT_LT(result.score, shippedAppearance().min_score);
        ++cases;
      }
    }
  }
  EXPECT_EQ(cases, 18);
}

TEST(FaceAppearance, AMismatchTurnsAFoundDetectionIntoARejectionWithItsScore) {
  const cv::Mat print = shippedPrint();
  const FaceAppearanceCheck check(print, kFaceWidthM, kFaceHeightM);
  const Eigen::Vector3d port(0.1, 0.0, 5.0);
  const cv::Mat image = scene(cellTexture(print.size(), 25, 4), port, 0.0, 1.0, 3.0);
  Detection detection = foundAt(port);
  const AppearanceResult result = confirmByAppearance(check, image, cv::Mat(), ourCamera(), shippedAppearance(), &detection);
  EXPECT_EQ(result.verdict, AppearanceVerdict::kNotTheTarget);
  EXPECT_FALSE(detection.found);
  EXPECT_EQ(detection.outcome, StageOutcome(AppearanceOutcome::kMismatch));
  EXPECT_STREQ(outcomeName(detection.outcome), "appearance_mismatch");
  EXPECT_TRUE(detection.appearance_judged);
  EXPECT_DOUBLE_EQ(detection.appearance_score, result.score);
  EXPECT_NE(detection.reason.find("appearance_min_score"), std::string::npos) << detection.reason;

  // The print itself there: kept, with its score.
  const cv::Mat target = scene(print, port, 0.0, 1.0, 3.0);
  Detection kept = foundAt(port);
  confirmByAppearance(check, target, cv::Mat(), ourCamera(), shippedAppearance(), &kept);
  EXPECT_TRUE(kept.found) << kept.reason;
  EXPECT_GE(kept.appearance_score, 0.6);
}

// Unjudged either way; in the dark the blob stands, in glare it is invalid (the blob left by glare is the part
// of the mockup outside it: campaign seed 10939, the port 0.2-0.4 m off).
TEST(FaceAppearance, AFaceSaturatedByGlareOrInTheDarkIsNotJudgedAndOnlyTheDarkOneKept) {
  const cv::Mat print = shippedPrint();
  const FaceAppearanceCheck check(print, kFaceWidthM, kFaceHeightM);
  const Eigen::Vector3d port(0.0, 0.0, 3.0);
  // Glare: the left 60 % of the face white.
  cv::Mat glare = scene(print, port, 0.0, 1.0, 2.0);
  const int face_w = static_cast<int>(550.0 * kFaceWidthM / 3.0), face_h = static_cast<int>(550.0 * kFaceHeightM / 3.0);
  glare(cv::Rect(320 - face_w / 2 - 5, 240 - face_h / 2 - 5, face_w * 6 / 10 + 5, face_h + 10)).setTo(255);
  Detection detection = foundAt(port);
  const AppearanceResult glare_result = confirmByAppearance(check, glare, cv::Mat(), ourCamera(), shippedAppearance(), &detection);
  EXPECT_EQ(glare_result.verdict, AppearanceVerdict::kGlare) << glare_result.reason;
  EXPECT_GT(glare_result.saturated_fraction, 0.5);
  EXPECT_FALSE(detection.found);
  EXPECT_EQ(detection.outcome, StageOutcome(AppearanceOutcome::kGlare));
  EXPECT_NE(detection.reason.find("glare"), std::string::npos) << detection.reason;
  EXPECT_FALSE(detection.appearance_judged);

  // Dark: the room and the face at a tenth of their light.
  cv::Mat dark;
  scene(cellTexture(print.size(), 25, 5), port, 0.0, 1.0, 2.0).convertTo(dark, CV_8UC1, 0.1);
  const AppearanceResult dark_result = check.check(dark, ourCamera(), port, shippedAppearance());
  EXPECT_EQ(dark_result.verdict, AppearanceVerdict::kTooDark) << dark_result.reason;
  EXPECT_TRUE(isUnjudged(dark_result.verdict));
  Detection in_the_dark = foundAt(port);
  confirmByAppearance(check, dark, cv::Mat(), ourCamera(), shippedAppearance(), &in_the_dark);
  EXPECT_TRUE(in_the_dark.found) << in_the_dark.reason;
}

TEST(FaceAppearance, AFaceOutsideTheImageOrBadInputIsNotJudged) {
  const cv::Mat print = shippedPrint();
  const FaceAppearanceCheck check(print, kFaceWidthM, kFaceHeightM);
  const cv::Mat image = scene(print, Eigen::Vector3d(0.0, 0.0, 3.0), 0.0, 1.0, 2.0);
  EXPECT_EQ(check.check(image, ourCamera(), Eigen::Vector3d(2.0, 0.0, 3.0), shippedAppearance()).verdict,
            AppearanceVerdict::kOutsideImage);
  EXPECT_EQ(check.check(cv::Mat(), ourCamera(), Eigen::Vector3d(0.0, 0.0, 3.0), shippedAppearance()).verdict,
            AppearanceVerdict::kNotChecked);
  cv::Mat colour;
  cv::cvtColor(image, colour, cv::COLOR_GRAY2BGR);
  EXPECT_EQ(check.check(colour, ourCamera(), Eigen::Vector3d(0.0, 0.0, 3.0), shippedAppearance()).verdict,
            AppearanceVerdict::kNotChecked);
  EXPECT_EQ(check.check(image, ourCamera(), Eigen::Vector3d(0.0, 0.0, -3.0), shippedAppearance()).verdict,
            AppearanceVerdict::kNotChecked);
  EXPECT_EQ(FaceAppearanceCheck().check(image, ourCamera(), Eigen::Vector3d(0.0, 0.0, 3.0), shippedAppearance()).verdict,
            AppearanceVerdict::kNotChecked);
  EXPECT_THROW(FaceAppearanceCheck(cv::Mat(), kFaceWidthM, kFaceHeightM), std::invalid_argument);
  EXPECT_THROW(FaceAppearanceCheck(print, 0.0, kFaceHeightM), std::invalid_argument);
}

// The first setting of `params` the detector refuses, by its key.
std::string refusedKey(const DetectorParams& params) {
  try {
    validate(params, test::shippedShape(), test::shippedRig());
  } catch (const docking_settings::ConfigError& e) {
    return e.key();
  }
  return "";
}

TEST(FaceAppearance, InvalidSettingsAreNamed) {
  EXPECT_EQ(refusedKey(test::shippedParams()), "");
  DetectorParams params = test::shippedParams();
  params.appearance.min_score = 1.5;
  EXPECT_EQ(refusedKey(params), "appearance_min_score");
  params = test::shippedParams();
  params.appearance.max_saturated_fraction = 1.5;
  EXPECT_EQ(refusedKey(params), "appearance_max_saturated_fraction");
}

}  // namespace
}  // namespace disparity
}  // namespace docking_perception
