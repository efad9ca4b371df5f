#include <docking_perception/camera/calibration_check.h>

#include <gtest/gtest.h>

using docking_perception::camera::calibrationFileFromUrl;
using docking_perception::camera::calibrationSizeProblem;

TEST(CalibrationCheck, FileUrlBecomesAPath) {
  EXPECT_EQ(calibrationFileFromUrl("file:///work/config/cameras/ir.yaml"), "/work/config/cameras/ir.yaml");
  EXPECT_EQ(calibrationFileFromUrl("package://pkg/ir.yaml"), "package://pkg/ir.yaml");
}

TEST(CalibrationCheck, MatchingSizeOrNoCalibrationIsFine) {
  EXPECT_EQ(calibrationSizeProblem("/c/left.yaml", 640, 480, 640, 480, "frames"), "");
  EXPECT_EQ(calibrationSizeProblem("/c/left.yaml", 0, 0, 320, 240, "frames"), "");
}

TEST(CalibrationCheck, MismatchNamesFileAndBothSizes) {
  const std::string problem =
      calibrationSizeProblem("/c/left.yaml", 640, 480, 320, 240, "the frames of V4L2 device /dev/video0");
  ASSERT_FALSE(problem.empty());
  EXPECT_NE(problem.find("/c/left.yaml"), std::string::npos);
  EXPECT_NE(problem.find("640x480"), std::string::npos);
  EXPECT_NE(problem.find("320x240"), std::string::npos);
  EXPECT_NE(problem.find("/dev/video0"), std::string::npos);
  // Only one dimension off is still a mismatch.
  EXPECT_FALSE(calibrationSizeProblem("/c/left.yaml", 640, 480, 640, 360, "frames").empty());
}
