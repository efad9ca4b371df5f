#include <gtest/gtest.h>

#include <cstdio>
#include <fstream>
#include <opencv2/imgcodecs.hpp>
#include <string>
#include <sys/stat.h>
#include <unistd.h>

#include "docking_perception/mono/target_model.h"
#include "synthetic_scene.h"

using docking_perception::mono::TargetModel;
using docking_perception::mono::TargetModelError;
namespace synthetic = docking_perception::mono::synthetic;

namespace {

// A private scratch folder with a yaml and a texture, removed at the end of each test.
class TargetYamlTest : public ::testing::Test {
 protected:
  void SetUp() override {
    char pattern[] = "/tmp/mono_target_model_XXXXXX";
    ASSERT_NE(mkdtemp(pattern), nullptr);
    dir_ = pattern;
    mkdir((dir_ + "/textures").c_str(), 0755);
    ASSERT_TRUE(cv::imwrite(dir_ + "/textures/face.png", synthetic::makeTexture(3)));
  }
  void TearDown() override {
    std::remove((dir_ + "/textures/face.png").c_str());
    std::remove((dir_ + "/target.yaml").c_str());
    rmdir((dir_ + "/textures").c_str());
    rmdir(dir_.c_str());
  }
  std::string writeYaml(const std::string& markers_line, const std::string& texture = "textures/face.png",
                        const std::string& width_line = "    width_m: 0.30\n") {
    const std::string path = dir_ + "/target.yaml";
    std::ofstream out(path);
    out << "target:\n  frame_id: target\n  face:\n" << width_line << "    height_m: 0.24\n    texture: " << texture
        << "\n  markers_m: " << markers_line << "\n  marker_radius_m: 0.010\n  led_radius_m: 0.005\n";
    return path;
  }
  std::string dir_;
};

const char kGoodMarkers[] =
    "[[0.0, 0.11, 0.09], [0.0, 0.0, 0.09], [0.0, -0.11, 0.09], [0.0, -0.11, 0.01], [0.0, -0.11, -0.07]]";

std::string loadError(const std::string& path) {
  try {
    TargetModel::loadFromYaml(path);
  } catch (const TargetModelError& e) {
    return e.what();
  }
  return "";
}

}  // namespace

TEST_F(TargetYamlTest, LoadsGeometryAndTextureRelativeToTheYamlFolder) {
  const TargetModel model = TargetModel::loadFromYaml(writeYaml(kGoodMarkers));
  EXPECT_DOUBLE_EQ(model.faceWidth(), 0.30);
  EXPECT_DOUBLE_EQ(model.faceHeight(), 0.24);
  EXPECT_DOUBLE_EQ(model.markers()[4].z(), -0.07);
  ASSERT_TRUE(model.hasTexture());
  EXPECT_EQ(model.textureGray().cols, 600);
  EXPECT_EQ(model.textureGray().rows, 480);
}

TEST_F(TargetYamlTest, MissingFieldIsNamedWithTheFile) {
  const std::string path = writeYaml(kGoodMarkers, "textures/face.png", "");
  const std::string error = loadError(path);
  EXPECT_NE(error.find(path), std::string::npos) << error;
  EXPECT_NE(error.find("target.face.width_m"), std::string::npos) << error;
}

TEST_F(TargetYamlTest, MarkerThatIsNotAMidpointIsRejected) {
  const std::string error = loadError(writeYaml(
      "[[0.0, 0.11, 0.09], [0.0, 0.01, 0.09], [0.0, -0.11, 0.09], [0.0, -0.11, 0.01], [0.0, -0.11, -0.07]]"));
  EXPECT_NE(error.find("target.markers_m[1]"), std::string::npos) << error;
}

TEST_F(TargetYamlTest, WrongMarkerCountAndOffPlaneMarkerAreRejected) {
  EXPECT_NE(loadError(writeYaml("[[0.0, 0.11, 0.09]]")).find("exactly 5"), std::string::npos);
  const std::string error = loadError(writeYaml(
      "[[0.01, 0.11, 0.09], [0.0, 0.0, 0.09], [0.0, -0.11, 0.09], [0.0, -0.11, 0.01], [0.0, -0.11, -0.07]]"));
  EXPECT_NE(error.find("target.markers_m[0]"), std::string::npos) << error;
}

TEST_F(TargetYamlTest, UnreadableTextureIsNamed) {
  const std::string error = loadError(writeYaml(kGoodMarkers, "textures/missing.png"));
  EXPECT_NE(error.find("target.face.texture"), std::string::npos) << error;
  EXPECT_NE(error.find("missing.png"), std::string::npos) << error;
}

TEST_F(TargetYamlTest, MissingFileIsReported) {
  const std::string error = loadError(dir_ + "/nothing.yaml");
  EXPECT_NE(error.find("nothing.yaml"), std::string::npos) << error;
}

TEST(TargetModel, TextureMappingFollowsTheFaceConvention) {
  const TargetModel model = synthetic::makeModel(1);
  // Outer texture corners are the face corners; u runs along +y, v along -z.
  const Eigen::Vector3d top_left = model.texturePixelToPoint(cv::Point2f(-0.5f, -0.5f));
  EXPECT_NEAR(top_left.x(), 0.0, 1e-12);
  EXPECT_NEAR(top_left.y(), -0.15, 1e-9);
  EXPECT_NEAR(top_left.z(), 0.12, 1e-9);
  const Eigen::Vector3d bottom_right = model.texturePixelToPoint(cv::Point2f(599.5f, 479.5f));
  EXPECT_NEAR(bottom_right.y(), 0.15, 1e-6);
  EXPECT_NEAR(bottom_right.z(), -0.12, 1e-6);
  const cv::Point2d back = model.pointToTexturePixel(model.markers()[0]);
  const Eigen::Vector3d again = model.texturePixelToPoint(cv::Point2f(static_cast<float>(back.x), static_cast<float>(back.y)));
  EXPECT_NEAR((again - model.markers()[0]).norm(), 0.0, 1e-6);
  const auto corners = model.faceCorners();
  ASSERT_EQ(corners.size(), 4u);
  EXPECT_NEAR((corners[0] - top_left).norm(), 0.0, 1e-9);
}

TEST(TargetModel, FromPartsValidatesArms) {
  auto markers = synthetic::defaultMarkers();
  // Both arms along y: parallel, the rotation would be undefined.
  markers[3] = Eigen::Vector3d(0.0, -0.05, 0.09);
  markers[4] = Eigen::Vector3d(0.0, 0.01, 0.09);
  EXPECT_THROW(TargetModel::fromParts(0.30, 0.24, markers, 0.01, 0.005, cv::Mat()), TargetModelError);
}
