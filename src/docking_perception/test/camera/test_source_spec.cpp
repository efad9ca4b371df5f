#include <docking_perception/camera/source_spec.h>

#include <gtest/gtest.h>

#include <stdexcept>

using docking_perception::camera::parseSourceSpec;
using docking_perception::camera::SourceKind;

TEST(SourceSpec, DigitsAreADeviceIndex) {
  const auto spec = parseSourceSpec(" 2 ");
  EXPECT_EQ(spec.kind, SourceKind::kDeviceIndex);
  EXPECT_EQ(spec.device_index, 2);
  EXPECT_EQ(spec.text, "2");
  EXPECT_TRUE(spec.isLiveDevice());
  EXPECT_NE(spec.describe().find("/dev/video2"), std::string::npos);
}

TEST(SourceSpec, DevPathsAreDevices) {
  EXPECT_EQ(parseSourceSpec("/dev/video1").kind, SourceKind::kDevicePath);
  const auto by_id = parseSourceSpec("/dev/v4l/by-id/usb-046d_0825-video-index0");
  EXPECT_EQ(by_id.kind, SourceKind::kDevicePath);
  EXPECT_TRUE(by_id.isLiveDevice());
}

TEST(SourceSpec, IntegerPatternIsAnImageSequence) {
  const auto spec = parseSourceSpec("/data/left_%04d.png");
  EXPECT_EQ(spec.kind, SourceKind::kImageSequence);
  EXPECT_FALSE(spec.isLiveDevice());
  EXPECT_EQ(parseSourceSpec("frame%d.jpg").kind, SourceKind::kImageSequence);
}

TEST(SourceSpec, AnythingElseIsAVideoFile) {
  EXPECT_EQ(parseSourceSpec("/bags/approach.mp4").kind, SourceKind::kVideoFile);
  EXPECT_EQ(parseSourceSpec("rtsp://camera.local/stream").kind, SourceKind::kVideoFile);
  EXPECT_EQ(parseSourceSpec("video0").kind, SourceKind::kVideoFile);  // not digits only
}

TEST(SourceSpec, RejectsWhatCannotBeASource) {
  EXPECT_THROW(parseSourceSpec(""), std::invalid_argument);
  EXPECT_THROW(parseSourceSpec("   "), std::invalid_argument);
  EXPECT_THROW(parseSourceSpec("-1"), std::invalid_argument);
  EXPECT_THROW(parseSourceSpec("123456"), std::invalid_argument);
  EXPECT_THROW(parseSourceSpec("left_%s.png"), std::invalid_argument);
  EXPECT_THROW(parseSourceSpec("left_%d_%d.png"), std::invalid_argument);
  EXPECT_THROW(parseSourceSpec("left_100%"), std::invalid_argument);
}

TEST(SourceSpec, ErrorNamesTheText) {
  try {
    parseSourceSpec("cam_%x.png");
    FAIL() << "expected std::invalid_argument";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("cam_%x.png"), std::string::npos) << e.what();
  }
}
