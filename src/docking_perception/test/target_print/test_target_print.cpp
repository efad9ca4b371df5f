// The user's own target (issue 11): make_target_print's composition and check_target_print's check.
// Prints are procedural (fixed seeds, no downloads); the shipped config/target.yaml is checked too.
#include <algorithm>
#include <cmath>
#include <random>
#include <stdexcept>
#include <string>

#include <iostream>

#include <gtest/gtest.h>
#include <opencv2/imgproc.hpp>

#include "docking_perception/target_print/target_print.h"
#include "docking_settings/yaml_loader.h"

namespace docking_perception {
namespace target_print {
namespace {

const std::string kConfigDir = TARGET_PRINT_CONFIG_DIR;

// The shipped visible configuration.
mono::MonoPoseParams visibleParams() {
  return docking_settings::shippedSettings<mono::MonoPoseNodeSettings>(kConfigDir + "/mono_pose_visible.yaml").core;
}

const mono::TargetModel& shippedModel() {
  static const mono::TargetModel model = mono::TargetModel::loadFromYaml(kConfigDir + "/target.yaml");
  return model;
}

mono::TargetModel withPrint(const cv::Mat& print) {
  const mono::TargetModel& m = shippedModel();
  return mono::TargetModel::fromParts(m.faceWidth(), m.faceHeight(), m.markers(), m.markerRadius(),
                                      m.ledRadius(), print);
}

// The check, its table printed for the test log (the figures the README quotes).
PrintReport check(const mono::TargetModel& model) {
  const mono::MonoPoseParams params = visibleParams();
  const PrintReport report = checkPrint(model, params.features, CheckParams());
  std::cout << formatReport(report, CheckParams());
  return report;
}

bool hasProblem(const PrintReport& report, PrintProblem problem) {
  return std::find(report.problems.begin(), report.problems.end(), problem) != report.problems.end();
}

// A busy "photograph": smooth colour blobs, objects with sharp edges at many sizes, fine strokes, and
// dark regions, one of them over the left markers (where bare dots vanish).
cv::Mat busyPhotograph(unsigned seed) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> unit(0.0, 1.0);
  auto colour = [&](double scale) {
    return cv::Scalar(scale * 255 * unit(rng), scale * 255 * unit(rng), scale * 255 * unit(rng));
  };
  auto point = [&](cv::Size size) {
    return cv::Point(static_cast<int>(unit(rng) * size.width), static_cast<int>(unit(rng) * size.height));
  };
  const cv::Size size(1000, 800);
  // Smooth colour blobs: random colours on a coarse grid, upscaled smoothly.
  cv::Mat coarse(8, 10, CV_8UC3);
  for (int v = 0; v < coarse.rows; ++v) {
    for (int u = 0; u < coarse.cols; ++u) {
      const cv::Scalar c = colour(1.0);
      coarse.at<cv::Vec3b>(v, u) = cv::Vec3b(static_cast<std::uint8_t>(c[0]), static_cast<std::uint8_t>(c[1]),
                                             static_cast<std::uint8_t>(c[2]));
    }
  }
  cv::Mat photo;
  cv::resize(coarse, photo, size, 0, 0, cv::INTER_CUBIC);
  for (int i = 0; i < 160; ++i) {  // objects: sharp-edged ellipses and boxes, 10-120 px
    const cv::Point centre = point(size);
    const cv::Size axes(static_cast<int>(5 + 55 * unit(rng)), static_cast<int>(5 + 55 * unit(rng)));
    if (unit(rng) < 0.5) {
      cv::ellipse(photo, centre, axes, 180 * unit(rng), 0, 360, colour(1.0), cv::FILLED, cv::LINE_AA);
    } else {
      cv::rectangle(photo, cv::Rect(centre, axes), colour(1.0), cv::FILLED);
    }
  }
  for (int i = 0; i < 600; ++i) {  // fine detail: short strokes of any level
    const cv::Point a = point(size);
    const cv::Point b = a + cv::Point(static_cast<int>(40 * unit(rng) - 20), static_cast<int>(40 * unit(rng) - 20));
    cv::line(photo, a, b, colour(1.0), 1 + static_cast<int>(3 * unit(rng)), cv::LINE_AA);
  }
  // Dark regions: the left fifth of the picture (markers 2-4 sit there) and a random ellipse.
  cv::Mat dark(size / 8, CV_32FC3, cv::Scalar(1, 1, 1));
  cv::rectangle(dark, cv::Rect(0, 0, dark.cols / 5, dark.rows), cv::Scalar(0.2, 0.2, 0.2), cv::FILLED);
  cv::ellipse(dark, point(dark.size()), cv::Size(22, 15), 30, 0, 360, cv::Scalar(0.25, 0.25, 0.25), cv::FILLED);
  cv::resize(dark, dark, size, 0, 0, cv::INTER_LINEAR);
  cv::Mat photo_float;
  photo.convertTo(photo_float, CV_32FC3);
  photo_float = photo_float.mul(dark);
  photo_float.convertTo(photo, CV_8UC3);
  return photo;
}

TEST(TargetPrint, TheShippedTargetPasses) {
  const PrintReport report = check(shippedModel());
  EXPECT_TRUE(report.passed) << formatReport(report, CheckParams());
  ASSERT_EQ(report.cases.size(), CheckParams().cases.size());
  for (const auto& c : report.cases) {
    EXPECT_TRUE(c.passed) << c.view.range_m << " m, " << c.view.yaw_deg << " deg";
    EXPECT_GE(c.inliers, report.required_inliers);
    EXPECT_EQ(c.dots_found, 5);
  }
}

TEST(TargetPrint, AFlatGradientFailsForTexture) {
  cv::Mat gradient(600, 750, CV_8UC3);
  for (int v = 0; v < gradient.rows; ++v) {
    for (int u = 0; u < gradient.cols; ++u) {
      const auto level = static_cast<std::uint8_t>(20 + 215 * u / gradient.cols);
      gradient.at<cv::Vec3b>(v, u) = cv::Vec3b(level, static_cast<std::uint8_t>(255 - level), 128);
    }
  }
  const PrintReport report = check(withPrint(composePrint(gradient, shippedModel())));
  EXPECT_FALSE(report.passed);
  EXPECT_TRUE(hasProblem(report, PrintProblem::kLowTexture)) << formatReport(report, CheckParams());
  EXPECT_FALSE(hasProblem(report, PrintProblem::kDotsLowContrast)) << "the composed dots are fine";
}

TEST(TargetPrint, ALowContrastPrintFailsForContrast) {
  // The shipped face, its levels squeezed to 128 +- 15 %: a pale, foggy print.
  cv::Mat pale;
  shippedModel().textureGray().convertTo(pale, CV_8U, 0.15, 128 * 0.85);
  const PrintReport report = check(withPrint(pale));
  EXPECT_FALSE(report.passed);
  EXPECT_TRUE(hasProblem(report, PrintProblem::kLowContrast)) << formatReport(report, CheckParams());
  EXPECT_LT(report.print_contrast_dn, CheckParams().min_print_contrast_dn);
}

TEST(TargetPrint, ABusyPhotographComposedWithTheToolPassesAndItsDotsAreFound) {
  const cv::Mat print = composePrint(busyPhotograph(5), shippedModel());
  const PrintReport report = check(withPrint(print));
  EXPECT_TRUE(report.passed) << formatReport(report, CheckParams());
  for (const auto& c : report.cases) {
    EXPECT_EQ(c.dots_found, 5) << c.view.range_m << " m, " << c.view.yaw_deg << " deg";
  }
}

TEST(TargetPrint, TheSamePhotographWithBareDotsIsFlagged) {
  // Dots drawn straight onto the dark, busy picture (no rings): what the user printed.
  // The same centred crop as composePrint (the picture is wider than the face), then bare dots.
  const mono::TargetModel& m = shippedModel();
  const cv::Mat photo = busyPhotograph(5);
  const int height = static_cast<int>(std::lround(photo.cols * m.faceHeight() / m.faceWidth()));
  cv::Mat bare;
  cv::resize(photo(cv::Rect(0, (photo.rows - height) / 2, photo.cols, height)), bare,
             cv::Size(1800, static_cast<int>(std::lround(1800 * m.faceHeight() / m.faceWidth()))), 0, 0,
             cv::INTER_AREA);
  const mono::TargetModel bare_model = withPrint(bare);
  const double radius_px = m.markerRadius() * bare.cols / m.faceWidth();
  for (const auto& marker : m.markers()) {
    const cv::Point2d centre = bare_model.pointToTexturePixel(marker);
    cv::circle(bare, cv::Point(static_cast<int>(std::lround(centre.x)), static_cast<int>(std::lround(centre.y))),
               static_cast<int>(std::lround(radius_px)), cv::Scalar(15, 15, 15), cv::FILLED, cv::LINE_AA);
  }
  const PrintReport report = check(withPrint(bare));
  EXPECT_FALSE(report.passed);
  EXPECT_TRUE(hasProblem(report, PrintProblem::kDotsLowContrast) ||
              hasProblem(report, PrintProblem::kDotsNotFound))
      << formatReport(report, CheckParams());
}

TEST(ComposePrint, DotsOnWhiteRingsAtTheMarkerPositions) {
  const mono::TargetModel& m = shippedModel();
  ComposeOptions options;
  options.width_px = 900;
  const cv::Mat print = composePrint(busyPhotograph(9), m, options);
  ASSERT_EQ(print.cols, 900);
  EXPECT_NEAR(static_cast<double>(print.cols) / print.rows, m.faceWidth() / m.faceHeight(), 0.01);
  const mono::TargetModel model = withPrint(print);
  const double radius_px = m.markerRadius() * print.cols / m.faceWidth();
  for (const auto& marker : m.markers()) {
    const cv::Point2d centre = model.pointToTexturePixel(marker);
    const cv::Vec3b dot = print.at<cv::Vec3b>(cv::Point(static_cast<int>(std::lround(centre.x)),
                                                        static_cast<int>(std::lround(centre.y))));
    EXPECT_LE(dot[0], 20);
    const cv::Vec3b ring = print.at<cv::Vec3b>(cv::Point(
        static_cast<int>(std::lround(centre.x + 1.8 * radius_px)), static_cast<int>(std::lround(centre.y))));
    EXPECT_GE(ring[0], 250);
    EXPECT_GE(ring[2], 250);
  }
}

TEST(ComposePrint, BadInputIsRefused) {
  EXPECT_THROW(composePrint(cv::Mat(), shippedModel()), std::invalid_argument);
  EXPECT_THROW(composePrint(cv::Mat(8, 8, CV_8UC3), shippedModel()), std::invalid_argument);
  EXPECT_THROW(composePrint(cv::Mat(100, 100, CV_32FC1), shippedModel()), std::invalid_argument);
  ComposeOptions narrow_ring;
  narrow_ring.ring_outer_factor = 1.2;  // inside the dot finder's 1.5-radius search disc
  EXPECT_THROW(composePrint(cv::Mat(100, 100, CV_8UC3, cv::Scalar(0)), shippedModel(), narrow_ring),
               std::invalid_argument);
}

TEST(CheckPrint, BadParametersAndAModelWithoutTextureAreRefused) {
  CheckParams params;
  params.min_views_passed = params.views_per_case + 1;
  EXPECT_FALSE(validateCheckParams(params).empty());
  const mono::MonoPoseParams mono_params = visibleParams();
  EXPECT_THROW(checkPrint(shippedModel(), mono_params.features, params),
               std::invalid_argument);
  const mono::TargetModel& m = shippedModel();
  const mono::TargetModel no_texture = mono::TargetModel::fromParts(
      m.faceWidth(), m.faceHeight(), m.markers(), m.markerRadius(), m.ledRadius(), cv::Mat());
  EXPECT_THROW(checkPrint(no_texture, mono_params.features), std::invalid_argument);
}

}  // namespace
}  // namespace target_print
}  // namespace docking_perception
