// The image guard's check: each malformed image gives its own code; good images of every kind pass.
#include <gtest/gtest.h>

#include <limits>
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
  const ImageLimits limits{1u << 31, 0.5};
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

}  // namespace
}  // namespace image_guard
}  // namespace docking_perception
