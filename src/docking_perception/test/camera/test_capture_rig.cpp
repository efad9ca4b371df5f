#include <docking_perception/camera/capture_rig.h>

#include <gtest/gtest.h>
#include <opencv2/imgcodecs.hpp>

#include <cstdlib>
#include <filesystem>
#include <string>

namespace fs = std::filesystem;
using docking_perception::camera::BackoffParams;
using docking_perception::camera::CaptureRig;
using docking_perception::camera::CaptureSettings;
using docking_perception::camera::CaptureStatus;
using docking_perception::camera::parseSourceSpec;

namespace {

// A fresh directory per test, removed afterwards.
class CaptureRigTest : public ::testing::Test {
 protected:
  void SetUp() override {
    std::string pattern = (fs::temp_directory_path() / "camera_rig_test_XXXXXX").string();
    ASSERT_NE(mkdtemp(pattern.data()), nullptr);
    dir_ = pattern;
  }
  void TearDown() override { fs::remove_all(dir_); }

  // Writes `count` frames named <prefix>_0000.png ... whose pixels all equal base + 10 * index.
  std::string writeSequence(const std::string& prefix, int count, int base, cv::Size size = {32, 24}) {
    for (int i = 0; i < count; ++i) {
      char name[64];
      std::snprintf(name, sizeof(name), "%s_%04d.png", prefix.c_str(), i);
      cv::imwrite((dir_ / name).string(), cv::Mat(size, CV_8UC3, cv::Scalar::all(base + 10 * i)));
    }
    return (dir_ / (prefix + "_%04d.png")).string();
  }

  static int pixel(const cv::Mat& frame) { return frame.at<cv::Vec3b>(0, 0)[0]; }

  fs::path dir_;
  CaptureSettings settings_;
  BackoffParams backoff_{0.5, 2.0, 2.0};
};

TEST_F(CaptureRigTest, StereoSequenceGivesPairsInOrderThenEnds) {
  const std::string left = writeSequence("left", 3, 10);
  const std::string right = writeSequence("right", 3, 15);
  settings_.loop_files = false;
  CaptureRig rig({parseSourceSpec(left), parseSourceSpec(right)}, settings_, backoff_);

  for (int i = 0; i < 3; ++i) {
    int grabs = 0;
    const auto outcome = rig.capture(0.1 * i, [&grabs] { ++grabs; });
    ASSERT_EQ(outcome.status, CaptureStatus::kFrames) << outcome.message;
    ASSERT_EQ(outcome.frames.size(), 2u);
    EXPECT_EQ(grabs, 1);  // one stamp per pair
    EXPECT_EQ(pixel(outcome.frames[0]), 10 + 10 * i);  // left first, in file order
    EXPECT_EQ(pixel(outcome.frames[1]), 15 + 10 * i);
  }
  const auto end = rig.capture(1.0);
  EXPECT_EQ(end.status, CaptureStatus::kEndOfStream);
  EXPECT_NE(end.message.find("left_%04d.png"), std::string::npos) << end.message;
  EXPECT_EQ(rig.capture(2.0).status, CaptureStatus::kEndOfStream);  // stays ended
}

TEST_F(CaptureRigTest, PairEndsWithItsShorterSequence) {
  const std::string left = writeSequence("left", 3, 10);
  const std::string right = writeSequence("right", 2, 15);
  settings_.loop_files = false;
  CaptureRig rig({parseSourceSpec(left), parseSourceSpec(right)}, settings_, backoff_);
  EXPECT_EQ(rig.capture(0.0).status, CaptureStatus::kFrames);
  EXPECT_EQ(rig.capture(0.1).status, CaptureStatus::kFrames);
  EXPECT_EQ(rig.capture(0.2).status, CaptureStatus::kEndOfStream);
}

TEST_F(CaptureRigTest, LoopingSequenceStartsAgain) {
  const std::string ir = writeSequence("ir", 2, 100);
  CaptureRig rig({parseSourceSpec(ir)}, settings_, backoff_);
  EXPECT_EQ(pixel(rig.capture(0.0).frames.at(0)), 100);
  EXPECT_EQ(pixel(rig.capture(0.1).frames.at(0)), 110);
  EXPECT_EQ(rig.capture(0.2).status, CaptureStatus::kRestarted);
  const auto again = rig.capture(0.2);
  ASSERT_EQ(again.status, CaptureStatus::kFrames) << again.message;
  EXPECT_EQ(pixel(again.frames.at(0)), 100);
  EXPECT_EQ(rig.consecutiveFailures(), 0);
}

TEST_F(CaptureRigTest, MissingDeviceRetriesWithGrowingDelays) {
  const std::string device = "/dev/video_missing_for_camera_rig_test";
  CaptureRig rig({parseSourceSpec(device)}, settings_, backoff_);

  auto first = rig.capture(10.0);
  EXPECT_EQ(first.status, CaptureStatus::kWaiting);
  EXPECT_TRUE(first.new_failure);
  EXPECT_NE(first.message.find(device), std::string::npos) << first.message;
  EXPECT_DOUBLE_EQ(first.retry_at_s, 10.5);

  // Before the retry time nothing is attempted.
  auto waiting = rig.capture(10.4);
  EXPECT_EQ(waiting.status, CaptureStatus::kWaiting);
  EXPECT_FALSE(waiting.new_failure);
  EXPECT_EQ(rig.consecutiveFailures(), 1);

  EXPECT_DOUBLE_EQ(rig.capture(10.5).retry_at_s, 11.5);   // +1.0
  EXPECT_DOUBLE_EQ(rig.capture(11.5).retry_at_s, 13.5);   // +2.0
  EXPECT_DOUBLE_EQ(rig.capture(13.5).retry_at_s, 15.5);   // capped at max_s
  EXPECT_EQ(rig.consecutiveFailures(), 4);
  EXPECT_FALSE(rig.isOpen());
}

TEST_F(CaptureRigTest, DeviceThatExistsButIsNoCameraIsNamedAndRetried) {
  CaptureRig rig({parseSourceSpec("/dev/null")}, settings_, backoff_);
  const auto outcome = rig.capture(0.0);
  EXPECT_EQ(outcome.status, CaptureStatus::kWaiting);
  EXPECT_TRUE(outcome.new_failure);
  EXPECT_NE(outcome.message.find("cannot open V4L2 device /dev/null"), std::string::npos) << outcome.message;
  EXPECT_DOUBLE_EQ(outcome.retry_at_s, 0.5);
}

TEST_F(CaptureRigTest, OneMissingSourceKeepsThePairClosedAndIsNamed) {
  const std::string left = writeSequence("left", 2, 10);
  const std::string right = (dir_ / "absent_%04d.png").string();
  CaptureRig rig({parseSourceSpec(left), parseSourceSpec(right)}, settings_, backoff_);
  const auto outcome = rig.capture(0.0);
  EXPECT_EQ(outcome.status, CaptureStatus::kWaiting);
  EXPECT_NE(outcome.message.find("absent_%04d.png"), std::string::npos) << outcome.message;
  EXPECT_TRUE(outcome.frames.empty());
  EXPECT_FALSE(rig.isOpen());
}

TEST_F(CaptureRigTest, MissingVideoFileIsNamed) {
  const std::string video = (dir_ / "nothing_here.mp4").string();
  CaptureRig rig({parseSourceSpec(video)}, settings_, backoff_);
  const auto outcome = rig.capture(0.0);
  EXPECT_EQ(outcome.status, CaptureStatus::kWaiting);
  EXPECT_NE(outcome.message.find(video), std::string::npos) << outcome.message;
}

TEST_F(CaptureRigTest, SourceThatAppearsLaterIsPickedUpAndBackoffResets) {
  const std::string pattern = (dir_ / "late_%04d.png").string();
  CaptureRig rig({parseSourceSpec(pattern)}, settings_, backoff_);
  EXPECT_EQ(rig.capture(0.0).status, CaptureStatus::kWaiting);
  EXPECT_EQ(rig.capture(0.5).status, CaptureStatus::kWaiting);
  EXPECT_EQ(rig.consecutiveFailures(), 2);

  writeSequence("late", 2, 50);
  EXPECT_EQ(rig.capture(1.0).status, CaptureStatus::kWaiting);  // retry not due until 1.5
  const auto outcome = rig.capture(1.5);
  ASSERT_EQ(outcome.status, CaptureStatus::kFrames) << outcome.message;
  EXPECT_EQ(pixel(outcome.frames.at(0)), 50);
  EXPECT_EQ(rig.consecutiveFailures(), 0);
  EXPECT_TRUE(rig.isOpen());
  EXPECT_EQ(rig.openedSizes().at(0), cv::Size(32, 24));
}

TEST(CaptureRigSettings, InvalidSettingsAreRejected) {
  CaptureSettings settings;
  settings.fourcc = "MJPEG";
  EXPECT_THROW(CaptureRig({parseSourceSpec("0")}, settings, BackoffParams{}), std::invalid_argument);
  settings = CaptureSettings{};
  settings.width = 0;
  EXPECT_THROW(CaptureRig({parseSourceSpec("0")}, settings, BackoffParams{}), std::invalid_argument);
  EXPECT_THROW(CaptureRig({}, CaptureSettings{}, BackoffParams{}), std::invalid_argument);
}

}  // namespace
