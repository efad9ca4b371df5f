// The image guard's check: each malformed image gives its own code; good images of every kind pass.
#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <optional>
#include <stdexcept>

#include "docking_perception/image_guard/image_check.h"

namespace docking_perception {
namespace image_guard {
namespace {

constexpr double kNow = 100.0;

ImageFacts goodMono8() {
  ImageFacts f;
  f.encoding = "mono8";
  f.width = 640;
  f.height = 480;
  f.step = 640;
  f.data_size = 640u * 480u;
  f.frame_id = "ir_optical_frame";
  f.stamp_s = kNow;
  return f;
}

TEST(ImageCheck, GoodImagesPass) {
  const ImageLimits limits;
  EXPECT_EQ(checkImage(goodMono8(), kNow, limits), ImageProblem::kNone);
  ImageFacts bgr = goodMono8();
  bgr.encoding = "bgr8";
  bgr.step = 640 * 3 + 64;  // padded rows are fine
  bgr.data_size = static_cast<std::uint64_t>(bgr.step) * bgr.height;
  EXPECT_EQ(checkImage(bgr, kNow, limits), ImageProblem::kNone);
  ImageFacts old = goodMono8();
  old.stamp_s = 1.0;  // a bag's old stamps: not the guard's business
  EXPECT_EQ(checkImage(old, kNow, limits), ImageProblem::kNone);
}

TEST(ImageCheck, EachMalformedKindHasItsCode) {
  const ImageLimits limits;
  ImageFacts f = goodMono8();
  f.encoding = "foo";
  EXPECT_EQ(checkImage(f, kNow, limits), ImageProblem::kUnknownEncoding);
  f.encoding = "";
  EXPECT_EQ(checkImage(f, kNow, limits), ImageProblem::kUnknownEncoding);

  f = goodMono8();
  f.width = f.height = f.step = 0;
  f.data_size = 0;
  EXPECT_EQ(checkImage(f, kNow, limits), ImageProblem::kZeroSize);

  f = goodMono8();
  f.data_size -= 1;  // truncated
  EXPECT_EQ(checkImage(f, kNow, limits), ImageProblem::kDataSizeMismatch);

  f = goodMono8();
  f.step = 639;
  f.data_size = 639u * 480u;
  EXPECT_EQ(checkImage(f, kNow, limits), ImageProblem::kStepTooSmall);

  f = goodMono8();  // a 16-bit image whose rows do not start on a whole pixel (cv::Mat throws on it)
  f.encoding = "mono16";
  f.step = 1281;
  f.data_size = 1281u * 480u;
  EXPECT_EQ(checkImage(f, kNow, limits), ImageProblem::kStepNotAligned);

  f = goodMono8();
  f.width = f.height = 100000;  // huge dimensions, small data
  f.step = 100000;
  EXPECT_EQ(checkImage(f, kNow, limits), ImageProblem::kTooLarge);

  f = goodMono8();
  f.is_bigendian = 7;
  EXPECT_EQ(checkImage(f, kNow, limits), ImageProblem::kBadEndianFlag);

  f = goodMono8();  // big-endian 16-bit: debayer's cvtColor threw on rgba16 and bayer_*16 (found by probe)
  f.encoding = "bayer_rggb16";
  f.step = 1280;
  f.data_size = 1280u * 480u;
  f.is_bigendian = 1;
  EXPECT_EQ(checkImage(f, kNow, limits), ImageProblem::kBigEndian16Bit);
  f.is_bigendian = 0;
  EXPECT_EQ(checkImage(f, kNow, limits), ImageProblem::kNone);
  f = goodMono8();
  f.is_bigendian = 1;  // one byte per channel: the flag means nothing
  EXPECT_EQ(checkImage(f, kNow, limits), ImageProblem::kNone);

  f = goodMono8();
  f.frame_id.clear();
  EXPECT_EQ(checkImage(f, kNow, limits), ImageProblem::kNoFrameId);

  f = goodMono8();
  f.stamp_s = kNow + 1000.0;
  EXPECT_EQ(checkImage(f, kNow, limits), ImageProblem::kStampInFuture);
  f.stamp_s = std::numeric_limits<double>::quiet_NaN();
  EXPECT_EQ(checkImage(f, kNow, limits), ImageProblem::kStampNotFinite);
}

TEST(ImageCheck, ForgedSizesDoNotOverflow) {
  const ImageLimits limits{std::numeric_limits<int>::max(), 0.5};
  ImageFacts f = goodMono8();
  f.encoding = "bgra16";  // 8 bytes per pixel: width * 8 overflows 32 bits
  f.width = 1u << 30;
  f.step = 1024;
  f.height = 1;
  f.data_size = 1024;
  EXPECT_EQ(checkImage(f, kNow, limits), ImageProblem::kStepTooSmall);
  f.width = 128;
  f.step = 0xFFFFFFFEu;  // even: a whole number of 16-bit channels
  f.height = 0xFFFFu;
  f.data_size = 0xFFFFFFFFu;  // step * height overflows 32 bits to something else
  EXPECT_EQ(checkImage(f, kNow, limits), ImageProblem::kDataSizeMismatch);
}

TEST(ImageCheck, BytesPerPixel) {
  EXPECT_EQ(bytesPerPixel("mono8"), 1u);
  EXPECT_EQ(bytesPerPixel("bgr8"), 3u);
  EXPECT_EQ(bytesPerPixel("mono16"), 2u);
  EXPECT_EQ(bytesPerPixel("bayer_grbg8"), 1u);
  EXPECT_EQ(bytesPerPixel("32FC1"), 0u);
  EXPECT_STREQ(imageProblemName(ImageProblem::kDataSizeMismatch), "data_size_mismatch");
}

TEST(ImageCheck, LimitsAreValidated) {
  EXPECT_NO_THROW(validate(ImageLimits{}));
  EXPECT_THROW(validate(ImageLimits{0, 0.5}), std::invalid_argument);
  EXPECT_THROW(validate(ImageLimits{4096, -1.0}), std::invalid_argument);
  EXPECT_THROW(validate(ImageLimits{4096, std::numeric_limits<double>::infinity()}), std::invalid_argument);
}

// A C270-like calibration of a 640 x 480 camera, as camera_info_manager publishes it.
CameraInfoFacts goodInfo() {
  CameraInfoFacts f;
  f.width = 640;
  f.height = 480;
  f.distortion_model = "plumb_bob";
  f.D = {0.05, -0.1, 0.001, 0.0, 0.0};
  f.K = {820.0, 0.0, 320.0, 0.0, 820.0, 240.0, 0.0, 0.0, 1.0};
  const double c = std::cos(0.01), s = std::sin(0.01);
  f.R = {c, -s, 0.0, s, c, 0.0, 0.0, 0.0, 1.0};
  f.P = {815.0, 0.0, 318.0, -49.0, 0.0, 815.0, 241.0, 0.0, 0.0, 0.0, 1.0, 0.0};
  f.frame_id = "stereo_left_optical_frame";
  f.stamp_s = kNow;
  return f;
}
constexpr ImageSize kVga{640, 480};

TEST(CameraInfoCheck, GoodInfosPass) {
  const ImageLimits limits;
  EXPECT_EQ(checkCameraInfo(goodInfo(), kVga, kNow, limits), CameraInfoProblem::kNone);
  CameraInfoFacts f = goodInfo();
  f.D.clear();  // no coefficients: no distortion
  EXPECT_EQ(checkCameraInfo(f, kVga, kNow, limits), CameraInfoProblem::kNone);
  f = goodInfo();
  f.binning_x = f.binning_y = 2;  // binned: the image is half the sensor
  EXPECT_EQ(checkCameraInfo(f, ImageSize{320, 240}, kNow, limits), CameraInfoProblem::kNone);
  f = goodInfo();
  f.roi_x_offset = 100;
  f.roi_y_offset = 50;
  f.roi_width = 320;
  f.roi_height = 200;
  EXPECT_EQ(checkCameraInfo(f, ImageSize{320, 200}, kNow, limits), CameraInfoProblem::kNone);
  f = goodInfo();
  f.distortion_model = "rational_polynomial";
  f.D = {0.1, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0};
  EXPECT_EQ(checkCameraInfo(f, kVga, kNow, limits), CameraInfoProblem::kNone);
}

TEST(CameraInfoCheck, EachMalformedKindHasItsCode) {
  const ImageLimits limits;
  CameraInfoFacts f = goodInfo();
  f.width = 0;
  EXPECT_EQ(checkCameraInfo(f, kVga, kNow, limits), CameraInfoProblem::kZeroSize);
  f = goodInfo();
  f.width = 1;
  f.height = 100000;  // what aborted rectify's cv::remap (message_fuzz)
  EXPECT_EQ(checkCameraInfo(f, kVga, kNow, limits), CameraInfoProblem::kTooLarge);
  f = goodInfo();
  f.binning_x = 1000;
  EXPECT_EQ(checkCameraInfo(f, kVga, kNow, limits), CameraInfoProblem::kBadBinningOrRoi);
  f = goodInfo();
  f.roi_x_offset = 600;
  f.roi_width = 100;  // past the sensor's right edge
  f.roi_height = 100;
  EXPECT_EQ(checkCameraInfo(f, kVga, kNow, limits), CameraInfoProblem::kBadBinningOrRoi);
  f = goodInfo();
  f.width = 1;
  f.height = 1;
  EXPECT_EQ(checkCameraInfo(f, kVga, kNow, limits), CameraInfoProblem::kSizeDiffersFromImage);
  EXPECT_EQ(checkCameraInfo(goodInfo(), std::nullopt, kNow, limits), CameraInfoProblem::kNoImageYet);
  f = goodInfo();
  f.distortion_model = "fisheye_of_my_own";
  EXPECT_EQ(checkCameraInfo(f, kVga, kNow, limits), CameraInfoProblem::kUnknownDistortionModel);
  f = goodInfo();
  f.D.push_back(0.0);
  EXPECT_EQ(checkCameraInfo(f, kVga, kNow, limits), CameraInfoProblem::kDistortionCountMismatch);
  f = goodInfo();
  f.P[2] = std::numeric_limits<double>::quiet_NaN();
  EXPECT_EQ(checkCameraInfo(f, kVga, kNow, limits), CameraInfoProblem::kNotFinite);
  f = goodInfo();
  f.K = {};  // an uncalibrated camera publishes zeros
  EXPECT_EQ(checkCameraInfo(f, kVga, kNow, limits), CameraInfoProblem::kUncalibrated);
  f = goodInfo();
  f.R = {};
  EXPECT_EQ(checkCameraInfo(f, kVga, kNow, limits), CameraInfoProblem::kRectificationNotRotation);
  f.R = {1.0, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, -1.0};  // orthonormal but a mirror
  EXPECT_EQ(checkCameraInfo(f, kVga, kNow, limits), CameraInfoProblem::kRectificationNotRotation);
  f = goodInfo();
  f.frame_id.clear();
  EXPECT_EQ(checkCameraInfo(f, kVga, kNow, limits), CameraInfoProblem::kNoFrameId);
  f = goodInfo();
  f.stamp_s = kNow + 1000.0;
  EXPECT_EQ(checkCameraInfo(f, kVga, kNow, limits), CameraInfoProblem::kStampInFuture);
}

TEST(CameraInfoCheck, EveryCodeHasAName) {
  for (std::size_t i = 0; i < kCameraInfoProblemCount; ++i) {
    EXPECT_STRNE(cameraInfoProblemName(static_cast<CameraInfoProblem>(i)), "unknown") << i;
  }
  for (std::size_t i = 0; i < kImageProblemCount; ++i) {
    EXPECT_STRNE(imageProblemName(static_cast<ImageProblem>(i)), "unknown") << i;
  }
}

}  // namespace
}  // namespace image_guard
}  // namespace docking_perception
