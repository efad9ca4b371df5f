// The inner pattern's core: target.yaml's `inner_pattern` block, the tag's grid corners, and the pose
// from a tag drawn at a known pose (an exact perspective warp of its print), bad input reported invalid.
#include <gtest/gtest.h>
#include <sys/stat.h>
#include <unistd.h>

#include <cstdio>
#include <fstream>
#include <opencv2/imgproc.hpp>
#include <random>
#include <string>

#include "docking_perception/mono/inner_pattern_detector.h"
#include "docking_perception/mono/target_model.h"
#include "synthetic_scene.h"

namespace mono = docking_perception::mono;

namespace {

const char kTargetHead[] =
    "target:\n  face: {width_m: 0.30, height_m: 0.24, texture: none.png}\n"
    "  markers_m: [[0.0, 0.11, 0.09], [0.0, 0.0, 0.09], [0.0, -0.11, 0.09], [0.0, -0.11, 0.01], "
    "[0.0, -0.11, -0.07]]\n  marker_radius_m: 0.010\n  led_radius_m: 0.005\n";

std::string writeTarget(const std::string& inner_block) {
  char pattern[] = "/tmp/inner_pattern_XXXXXX";
  const int fd = mkstemp(pattern);
  close(fd);
  std::ofstream(pattern) << kTargetHead << inner_block;
  return pattern;
}

std::string loadError(const std::string& inner_block) {
  const std::string path = writeTarget(inner_block);
  std::string error;
  try {
    mono::TargetModel::loadFromYaml(path, false);
  } catch (const mono::TargetModelError& e) {
    error = e.what();
  }
  std::remove(path.c_str());
  return error;
}

// The 640x480, f = 550 px camera of the synthetic scenes (one definition for the mono tests).
mono::CameraIntrinsics camera() { return mono::synthetic::defaultCamera(); }

mono::TagSpec innerTag() {
  mono::TagSpec tag;
  tag.id = 1;
  tag.size_m = 0.04;
  tag.center_m = Eigen::Vector3d(0.0, -0.05, 0.0);
  return tag;
}

// The tag's print (white ring included) on a grey background, seen by `camera` at camera_T_target:
// the print warped by the exact homography, a little blur and noise.
cv::Mat drawTag(const mono::TagSpec& tag, const Eigen::Isometry3d& camera_T_target, double blur_px, int seed) {
  cv::Mat image(480, 640, CV_8UC1, cv::Scalar(120));
  mono::synthetic::drawInnerPattern(&image, tag, camera(), camera_T_target);
  if (blur_px > 0) cv::GaussianBlur(image, image, cv::Size(), blur_px);
  cv::Mat noise(image.size(), CV_16SC1);
  cv::RNG rng(seed);
  rng.fill(noise, cv::RNG::NORMAL, 0, 2.0);
  cv::Mat out;
  image.convertTo(out, CV_16SC1);
  out += noise;
  out.convertTo(image, CV_8UC1);
  return image;
}

// Camera looking along -x of `target` at distance d, at lateral offset y (frame `target`).
Eigen::Isometry3d cameraTTarget(double d, double y, double yaw_rad) {
  Eigen::Matrix3d target_R_camera;
  target_R_camera.col(0) = Eigen::Vector3d(0, 1, 0);
  target_R_camera.col(1) = Eigen::Vector3d(0, 0, -1);
  target_R_camera.col(2) = Eigen::Vector3d(-1, 0, 0);
  Eigen::Isometry3d target_T_camera = Eigen::Isometry3d::Identity();
  target_T_camera.linear() = Eigen::AngleAxisd(yaw_rad, Eigen::Vector3d::UnitZ()) * target_R_camera;
  target_T_camera.translation() = Eigen::Vector3d(d, y, 0.0);
  return target_T_camera.inverse();
}

}  // namespace

TEST(InnerPatternYaml, ShippedTargetHasOne) {
  const mono::TargetModel model = mono::TargetModel::loadFromYaml(std::string(CONFIG_DIR) + "/target.yaml", false);
  ASSERT_TRUE(model.hasInnerPattern());
  EXPECT_EQ(model.innerPattern().family, "tag36h11");
  EXPECT_GT(model.innerPattern().size_m, 0.0);
  EXPECT_DOUBLE_EQ(model.innerPattern().center_m.x(), 0.0);
}

TEST(InnerPatternYaml, OptionalAndValidated) {
  EXPECT_EQ(loadError(""), "");
  const std::string good = "  inner_pattern: {type: apriltag, family: tag36h11, id: 1, size_m: 0.04, ";
  EXPECT_EQ(loadError(good + "center_m: [0.0, -0.05, 0.0]}\n"), "");
  EXPECT_NE(loadError(good + "center_m: [0.0, -0.13, 0.0]}\n").find("does not fit"), std::string::npos);
  EXPECT_NE(loadError(good + "center_m: [0.01, 0.0, 0.0]}\n").find("x = 0"), std::string::npos);
  EXPECT_NE(loadError("  inner_pattern: {type: dots, family: tag36h11, id: 1, size_m: 0.04, center_m: [0, 0, 0]}\n")
                .find("inner_pattern.type"),
            std::string::npos);
  EXPECT_NE(loadError("  inner_pattern: {type: apriltag, family: tag36h11, id: 1, center_m: [0, 0, 0]}\n")
                .find("inner_pattern.size_m"),
            std::string::npos);
}

TEST(InnerPatternDetector, GridCornersLieOnTheTag) {
  const mono::InnerPatternDetector detector(innerTag());
  ASSERT_GE(detector.gridPoints().size(), 20u);
  for (const auto& p : detector.gridPoints()) {
    EXPECT_DOUBLE_EQ(p.x(), 0.0);
    EXPECT_LE(std::abs(p.y() + 0.05), 0.02 + 1e-12);
    EXPECT_LE(std::abs(p.z()), 0.02 + 1e-12);
  }
}

TEST(InnerPatternDetector, PoseFromAnExactViewAtCloseRange) {
  mono::InnerPatternDetector detector(innerTag());
  int seed = 1;
  for (const double d : {0.08, 0.12, 0.2, 0.3, 0.4}) {
    for (const double yaw : {-0.15, 0.0, 0.2}) {
      const Eigen::Isometry3d truth = cameraTTarget(d, -0.05 + 0.1 * yaw * d, yaw);
      const cv::Mat image = drawTag(innerTag(), truth, d < 0.15 ? 2.5 : 0.8, ++seed);
      const mono::InnerPatternResult r = detector.detect(image, camera(), nullptr);
      ASSERT_TRUE(r.valid) << "d " << d << " yaw " << yaw << ": " << r.status;
      EXPECT_GE(r.pose_points, 20) << "d " << d;
      const double position_error = (r.pose.translation - truth.translation()).norm();
      const double angle_error_deg = mono::rotationAngleBetween(r.pose.rotation, truth.linear()) * 180 / M_PI;
      // Near contact (what the tag is for) 1 mm and 1 deg; at 0.2-0.4 m the 4 cm tag fixes its tilt to
      // a few degrees only, which moves the port by a few mm (the covariance says so: the sim test).
      if (d <= 0.12) {
        EXPECT_LT(position_error, 0.001) << "d " << d << " yaw " << yaw;
        EXPECT_LT(angle_error_deg, 1.0) << "d " << d << " yaw " << yaw;
      }
      EXPECT_LT(position_error, 0.03 * d) << "d " << d << " yaw " << yaw;
      EXPECT_TRUE(r.pose.covariance.allFinite());
      EXPECT_GT(r.pose.covariance(2, 2), 0.0);
    }
  }
}

TEST(InnerPatternDetector, NothingToSeeIsInvalidWithAReason) {
  mono::InnerPatternDetector detector(innerTag());
  const cv::Mat blank(480, 640, CV_8UC1, cv::Scalar(128));
  const mono::InnerPatternResult r = detector.detect(blank, camera(), nullptr);
  EXPECT_FALSE(r.valid);
  EXPECT_FALSE(r.status.empty());
  // Another tag of the family (id 0 drawn, id 1 wanted): not ours.
  mono::TagSpec other = innerTag();
  other.id = 0;
  const mono::InnerPatternResult wrong = detector.detect(drawTag(other, cameraTTarget(0.15, -0.05, 0.0), 1.0, 3),
                                                          camera(), nullptr);
  EXPECT_FALSE(wrong.valid);
  EXPECT_NE(wrong.status.find("not among"), std::string::npos) << wrong.status;
  // A tag too small in the image (3 m away) is refused, not trusted.
  const mono::InnerPatternResult far = detector.detect(drawTag(innerTag(), cameraTTarget(3.0, -0.05, 0.0), 0.0, 4),
                                                        camera(), nullptr);
  EXPECT_FALSE(far.valid);
}
