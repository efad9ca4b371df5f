#include <docking_perception/camera/camera_mounts.h>

#include <gtest/gtest.h>

#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <stdexcept>

namespace fs = std::filesystem;
using docking_perception::camera::loadRobotCameras;
using docking_perception::camera::quaternionFromFixedAxisRpy;

namespace {

constexpr double kHalfPi = M_PI / 2.0;

TEST(CameraMounts, ReadsTheWorkspaceRobotFile) {
  const auto robot = loadRobotCameras(std::string(DOCKING_CONFIG_DIR) + "/robot.yaml");
  EXPECT_EQ(robot.base_frame, "base_link");
  ASSERT_EQ(robot.cameras.size(), 3u);
  EXPECT_EQ(robot.cameras[0].name, "stereo_left");
  EXPECT_EQ(robot.cameras[0].frame_id, "stereo_left_optical_frame");
  EXPECT_EQ(robot.cameras[1].frame_id, "stereo_right_optical_frame");
  EXPECT_EQ(robot.cameras[2].frame_id, "ir_optical_frame");
  EXPECT_EQ(robot.cameras[2].calibration, "cameras/ir.yaml");
  EXPECT_NEAR(robot.cameras[0].xyz_m.y() - robot.cameras[1].xyz_m.y(), 0.10, 1e-12);  // the baseline
}

TEST(CameraMounts, OpticalFrameOfAForwardCameraFollowsRep103) {
  // rpy [-pi/2, 0, -pi/2]: optical z (forward) is base +x, optical x (right) is base -y, y (down) is -z.
  const Eigen::Matrix3d rotation = quaternionFromFixedAxisRpy({-kHalfPi, 0.0, -kHalfPi}).toRotationMatrix();
  EXPECT_TRUE((rotation * Eigen::Vector3d::UnitZ()).isApprox(Eigen::Vector3d::UnitX(), 1e-12));
  EXPECT_TRUE((rotation * Eigen::Vector3d::UnitX()).isApprox(-Eigen::Vector3d::UnitY(), 1e-12));
  EXPECT_TRUE((rotation * Eigen::Vector3d::UnitY()).isApprox(-Eigen::Vector3d::UnitZ(), 1e-12));
}

TEST(CameraMounts, RpyIsFixedAxisRollFirst) {
  // Fixed axes: roll about x, then yaw about the fixed z. x stays x under the roll, then the yaw turns it
  // to y. (Moving axes, roll applied last, would send x to z instead.)
  const Eigen::Matrix3d rotation = quaternionFromFixedAxisRpy({kHalfPi, 0.0, kHalfPi}).toRotationMatrix();
  EXPECT_TRUE((rotation * Eigen::Vector3d::UnitX()).isApprox(Eigen::Vector3d::UnitY(), 1e-12));
  EXPECT_TRUE((rotation * Eigen::Vector3d::UnitY()).isApprox(Eigen::Vector3d::UnitZ(), 1e-12));
}

class BrokenRobotFile : public ::testing::Test {
 protected:
  void SetUp() override {
    std::string pattern = (fs::temp_directory_path() / "robot_yaml_test_XXXXXX").string();
    ASSERT_NE(mkdtemp(pattern.data()), nullptr);
    dir_ = pattern;
  }
  void TearDown() override { fs::remove_all(dir_); }

  // Loads a robot file whose ir camera entry is `ir_entry`; returns the error message.
  std::string errorFor(const std::string& ir_entry) {
    const std::string path = (dir_ / "robot.yaml").string();
    std::ofstream(path) << "chaser:\n  base_frame: base_link\n  cameras:\n"
                        << "    stereo_left:\n      frame_id: left_optical\n      xyz_m: [0.1, 0.05, 0.25]\n"
                        << "      rpy_rad: [0, 0, 0]\n"
                        << "    ir:\n" << ir_entry;
    try {
      loadRobotCameras(path);
    } catch (const std::runtime_error& e) {
      EXPECT_NE(std::string(e.what()).find(path), std::string::npos) << e.what();
      return e.what();
    }
    return "no error";
  }

  fs::path dir_;
};

TEST_F(BrokenRobotFile, ValidEntryLoads) {
  EXPECT_EQ(errorFor("      frame_id: ir_optical\n      xyz_m: [0, 0, 0.3]\n      rpy_rad: [0, 0, 0]\n"), "no error");
}

TEST_F(BrokenRobotFile, ErrorsNameTheField) {
  EXPECT_NE(errorFor("      frame_id: ir_optical\n      rpy_rad: [0, 0, 0]\n").find("chaser.cameras.ir.xyz_m: missing"),
            std::string::npos);
  EXPECT_NE(errorFor("      frame_id: ir_optical\n      xyz_m: [0, 0]\n      rpy_rad: [0, 0, 0]\n")
                .find("chaser.cameras.ir.xyz_m: expected a list of 3 numbers"),
            std::string::npos);
  EXPECT_NE(errorFor("      frame_id: ir_optical\n      xyz_m: [0, 0, 0]\n      rpy_rad: [0, up, 0]\n")
                .find("chaser.cameras.ir.rpy_rad: element 1 is not a number"),
            std::string::npos);
  EXPECT_NE(errorFor("      xyz_m: [0, 0, 0]\n      rpy_rad: [0, 0, 0]\n").find("chaser.cameras.ir.frame_id: missing"),
            std::string::npos);
  EXPECT_NE(errorFor("      frame_id: left_optical\n      xyz_m: [0, 0, 0]\n      rpy_rad: [0, 0, 0]\n")
                .find("chaser.cameras.ir.frame_id: 'left_optical' is used by another camera"),
            std::string::npos);
  EXPECT_NE(errorFor("      frame_id: ir_optical\n      xyz_m: [0, .nan, 0]\n      rpy_rad: [0, 0, 0]\n")
                .find("not finite"),
            std::string::npos);
}

TEST_F(BrokenRobotFile, MissingFileAndBadYamlAreNamed) {
  const std::string missing = (dir_ / "nope.yaml").string();
  try {
    loadRobotCameras(missing);
    FAIL() << "expected an error";
  } catch (const std::runtime_error& e) {
    EXPECT_NE(std::string(e.what()).find(missing), std::string::npos);
  }
  const std::string bad = (dir_ / "bad.yaml").string();
  std::ofstream(bad) << "chaser: [unclosed\n";
  EXPECT_THROW(loadRobotCameras(bad), std::runtime_error);
  std::ofstream(bad) << "something_else: 1\n";
  try {
    loadRobotCameras(bad);
    FAIL() << "expected an error";
  } catch (const std::runtime_error& e) {
    EXPECT_NE(std::string(e.what()).find(": chaser: missing"), std::string::npos) << e.what();
  }
}

}  // namespace
