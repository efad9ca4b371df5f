#include <docking_perception/camera/frame_format.h>

#include <gtest/gtest.h>

using docking_perception::camera::ColourMode;
using docking_perception::camera::toPublishable;

TEST(FrameFormat, ColourStaysBgrForTheStereoPair) {
  cv::Mat frame(4, 6, CV_8UC3, cv::Scalar(10, 20, 30));
  const auto out = toPublishable(frame, ColourMode::kKeep);
  ASSERT_TRUE(out.ok()) << out.error;
  EXPECT_EQ(out.encoding, "bgr8");
  EXPECT_EQ(out.image.type(), CV_8UC3);
  EXPECT_EQ(out.image.at<cv::Vec3b>(2, 3), cv::Vec3b(10, 20, 30));
}

TEST(FrameFormat, GreyStaysMono) {
  cv::Mat frame(4, 6, CV_8UC1, cv::Scalar(77));
  for (auto mode : {ColourMode::kKeep, ColourMode::kMono}) {
    const auto out = toPublishable(frame, mode);
    ASSERT_TRUE(out.ok());
    EXPECT_EQ(out.encoding, "mono8");
    EXPECT_EQ(out.image.at<uint8_t>(1, 1), 77);
  }
}

TEST(FrameFormat, IrTurnsColourIntoLuminance) {
  // Pure blue, green and red columns: BT.601 luminance weights 0.114, 0.587, 0.299.
  cv::Mat frame(2, 3, CV_8UC3, cv::Scalar(0, 0, 0));
  frame.col(0).setTo(cv::Scalar(255, 0, 0));
  frame.col(1).setTo(cv::Scalar(0, 255, 0));
  frame.col(2).setTo(cv::Scalar(0, 0, 255));
  const auto out = toPublishable(frame, ColourMode::kMono);
  ASSERT_TRUE(out.ok());
  EXPECT_EQ(out.encoding, "mono8");
  ASSERT_EQ(out.image.type(), CV_8UC1);
  EXPECT_NEAR(out.image.at<uint8_t>(0, 0), 29, 1);
  EXPECT_NEAR(out.image.at<uint8_t>(0, 1), 150, 1);
  EXPECT_NEAR(out.image.at<uint8_t>(0, 2), 76, 1);
}

TEST(FrameFormat, BgraLosesAlpha) {
  cv::Mat frame(3, 3, CV_8UC4, cv::Scalar(1, 2, 3, 200));
  const auto out = toPublishable(frame, ColourMode::kKeep);
  ASSERT_TRUE(out.ok());
  EXPECT_EQ(out.encoding, "bgr8");
  EXPECT_EQ(out.image.at<cv::Vec3b>(0, 0), cv::Vec3b(1, 2, 3));
}

TEST(FrameFormat, RejectsEmptyAndUnsupportedFrames) {
  EXPECT_FALSE(toPublishable(cv::Mat(), ColourMode::kKeep).ok());
  const auto deep = toPublishable(cv::Mat(3, 3, CV_16UC1, cv::Scalar(1000)), ColourMode::kMono);
  EXPECT_FALSE(deep.ok());
  EXPECT_NE(deep.error.find("16U"), std::string::npos) << deep.error;
  EXPECT_FALSE(toPublishable(cv::Mat(3, 3, CV_8UC2), ColourMode::kKeep).ok());
}
