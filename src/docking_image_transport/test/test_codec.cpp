// The codec of the `compressed` transport: round trips, the format strings, JPEG error bounds, and that
// bad input gives an error code (never an exception, never a wrong image).
#include <gtest/gtest.h>

#include <opencv2/core.hpp>
#include <opencv2/imgproc.hpp>

#include <cstring>
#include <string>
#include <vector>

#include "docking_image_transport/codec.h"

namespace dit = docking_image_transport;

namespace {

// A camera-like test picture: smooth shading, sharp-edged shapes and sensor noise, fixed seed.
cv::Mat scene(int type, int width = 160, int height = 120) {
  cv::Mat bgr(height, width, CV_8UC3);
  for (int r = 0; r < height; ++r)
    for (int c = 0; c < width; ++c)
      bgr.at<cv::Vec3b>(r, c) = cv::Vec3b(static_cast<uchar>(40 + c), static_cast<uchar>(60 + r), static_cast<uchar>(100 + (r + c) / 4));
  cv::rectangle(bgr, {30, 20}, {80, 70}, {20, 200, 230}, cv::FILLED);
  cv::circle(bgr, {115, 60}, 25, {230, 40, 30}, cv::FILLED);
  cv::Mat noise(height, width, CV_8UC3);
  cv::RNG rng(42);
  rng.fill(noise, cv::RNG::NORMAL, 0, 3);
  bgr += noise;
  if (type == CV_8UC3) return bgr;
  cv::Mat grey;
  cv::cvtColor(bgr, grey, cv::COLOR_BGR2GRAY);
  if (type == CV_8UC1) return grey;
  cv::Mat wide;
  grey.convertTo(wide, CV_16UC1, 257.0);  // spread over 16 bits: the low byte matters too
  return wide;
}

dit::ImageView viewOf(const cv::Mat& m, const std::string& encoding) {
  dit::ImageView v;
  v.width = m.cols;
  v.height = m.rows;
  v.encoding = encoding;
  v.step = m.step;
  v.data = m.data;
  v.size = m.step * static_cast<std::size_t>(m.rows);
  return v;
}

cv::Mat matOf(const dit::Image& image, int type) {
  return cv::Mat(image.height, image.width, type, const_cast<std::uint8_t*>(image.data.data()), image.step).clone();
}

dit::EncodeSettings jpeg(int quality) {
  dit::EncodeSettings s;
  s.codec = dit::Codec::kJpeg;
  s.jpeg_quality = quality;
  return s;
}

dit::EncodeSettings png(int level = 3) {
  dit::EncodeSettings s;
  s.codec = dit::Codec::kPng;
  s.png_level = level;
  return s;
}

dit::DecodeResult roundTrip(const cv::Mat& m, const std::string& encoding, const dit::EncodeSettings& s) {
  const dit::EncodeResult e = dit::encode(viewOf(m, encoding), s);
  EXPECT_TRUE(e.ok()) << e.reason;
  return dit::decode(e.format, e.data.data(), e.data.size());
}

double meanAbsError(const cv::Mat& a, const cv::Mat& b) {
  cv::Mat diff;
  cv::absdiff(a, b, diff);
  const cv::Scalar m = cv::mean(diff);
  double sum = 0.0;
  for (int c = 0; c < a.channels(); ++c) sum += m[c];
  return sum / a.channels();
}

struct Case {
  const char* encoding;
  int type;
};
const Case kEightBit[] = {{"mono8", CV_8UC1}, {"bgr8", CV_8UC3}, {"rgb8", CV_8UC3}};

}  // namespace

TEST(Codec, FormatStringsFollowTheStandardConvention) {
  EXPECT_EQ(dit::encode(viewOf(scene(CV_8UC3), "bgr8"), jpeg(90)).format, "bgr8; jpeg compressed bgr8");
  EXPECT_EQ(dit::encode(viewOf(scene(CV_8UC3), "rgb8"), jpeg(90)).format, "rgb8; jpeg compressed bgr8");
  EXPECT_EQ(dit::encode(viewOf(scene(CV_8UC1), "mono8"), jpeg(90)).format, "mono8; jpeg compressed ");
  EXPECT_EQ(dit::encode(viewOf(scene(CV_8UC1), "mono8"), png()).format, "mono8; png compressed ");
  EXPECT_EQ(dit::encode(viewOf(scene(CV_8UC3), "bgr8"), png()).format, "bgr8; png compressed bgr8");
  EXPECT_EQ(dit::encode(viewOf(scene(CV_16UC1), "mono16"), png()).format, "mono16; png compressed ");
}

TEST(Codec, PngIsBitExactForEveryEncoding) {
  for (const Case& c : kEightBit) {
    const cv::Mat in = scene(c.type);
    for (int level : {0, 3, 9}) {
      const dit::DecodeResult d = roundTrip(in, c.encoding, png(level));
      ASSERT_TRUE(d.ok()) << c.encoding << ": " << d.reason;
      EXPECT_EQ(d.image.encoding, c.encoding);
      EXPECT_EQ(d.image.width, in.cols);
      EXPECT_EQ(d.image.height, in.rows);
      EXPECT_EQ(cv::norm(matOf(d.image, c.type), in, cv::NORM_INF), 0.0) << c.encoding << " level " << level;
    }
  }
  const cv::Mat wide = scene(CV_16UC1);
  const dit::DecodeResult d = roundTrip(wide, "mono16", png());
  ASSERT_TRUE(d.ok()) << d.reason;
  EXPECT_EQ(d.image.encoding, "mono16");
  EXPECT_EQ(cv::norm(matOf(d.image, CV_16UC1), wide, cv::NORM_INF), 0.0);
}

TEST(Codec, BigEndianMono16ComesBackInHostOrder) {
  const cv::Mat wide = scene(CV_16UC1);
  cv::Mat swapped = wide.clone();
  for (int r = 0; r < swapped.rows; ++r)
    for (int c = 0; c < swapped.cols; ++c) {
      std::uint16_t& v = swapped.at<std::uint16_t>(r, c);
      v = static_cast<std::uint16_t>((v >> 8) | (v << 8));
    }
  dit::ImageView view = viewOf(swapped, "mono16");
  view.is_bigendian = true;
  const dit::EncodeResult e = dit::encode(view, png());
  ASSERT_TRUE(e.ok()) << e.reason;
  const dit::DecodeResult d = dit::decode(e.format, e.data.data(), e.data.size());
  ASSERT_TRUE(d.ok()) << d.reason;
  EXPECT_EQ(cv::norm(matOf(d.image, CV_16UC1), wide, cv::NORM_INF), 0.0);
}

TEST(Codec, RowPaddingIsIgnored) {
  const cv::Mat big = scene(CV_8UC3, 200, 120);
  const cv::Mat roi = big(cv::Rect(0, 0, 160, 120));  // step 600 bytes, rows of 480
  const dit::DecodeResult d = roundTrip(roi, "bgr8", png());
  ASSERT_TRUE(d.ok()) << d.reason;
  EXPECT_EQ(d.image.step, 480u);
  EXPECT_EQ(cv::norm(matOf(d.image, CV_8UC3), roi, cv::NORM_INF), 0.0);
}

TEST(Codec, JpegErrorIsBoundedAndShrinksWithQuality) {
  for (const Case& c : kEightBit) {
    const cv::Mat in = scene(c.type);
    double previous_error = 1e9;
    std::size_t previous_bytes = 0;
    for (int quality : {50, 70, 90, 95}) {
      const dit::EncodeResult e = dit::encode(viewOf(in, c.encoding), jpeg(quality));
      ASSERT_TRUE(e.ok()) << e.reason;
      const dit::DecodeResult d = dit::decode(e.format, e.data.data(), e.data.size());
      ASSERT_TRUE(d.ok()) << d.reason;
      EXPECT_EQ(d.image.encoding, c.encoding);
      const double error = meanAbsError(matOf(d.image, c.type), in);
      EXPECT_LT(error, previous_error) << c.encoding << " q" << quality;
      EXPECT_GT(e.data.size(), previous_bytes) << c.encoding << " q" << quality;
      previous_error = error;
      previous_bytes = e.data.size();
      if (quality == 90) {
        // Grey levels: the noise (sigma 3) dominates what JPEG throws away at 90.
        EXPECT_LT(error, 3.0) << c.encoding;
        EXPECT_GT(error, 0.0) << c.encoding << ": JPEG should not be lossless";
      }
    }
  }
}

TEST(Codec, RgbChannelOrderSurvivesJpeg) {
  cv::Mat red_rgb(64, 64, CV_8UC3, cv::Scalar(250, 10, 10));  // R first in rgb8
  const dit::DecodeResult d = roundTrip(red_rgb, "rgb8", jpeg(90));
  ASSERT_TRUE(d.ok()) << d.reason;
  const cv::Scalar mean = cv::mean(matOf(d.image, CV_8UC3));
  EXPECT_GT(mean[0], 200.0);
  EXPECT_LT(mean[2], 50.0);
}

TEST(Codec, BareLegacyFormatDecodesByChannels) {
  const dit::EncodeResult grey = dit::encode(viewOf(scene(CV_8UC1), "mono8"), jpeg(90));
  const dit::EncodeResult colour = dit::encode(viewOf(scene(CV_8UC3), "bgr8"), png());
  EXPECT_EQ(dit::decode("jpeg", grey.data.data(), grey.data.size()).image.encoding, "mono8");
  EXPECT_EQ(dit::decode("png", colour.data.data(), colour.data.size()).image.encoding, "bgr8");
}

TEST(Codec, EncodeRejectsWhatItCannotEncode) {
  const cv::Mat bgr = scene(CV_8UC3);
  dit::EncodeResult r = dit::encode(viewOf(bgr, "bayer_rggb8"), png());
  EXPECT_EQ(r.error, dit::EncodeError::kUnsupportedEncoding);
  EXPECT_NE(r.reason.find("bayer_rggb8"), std::string::npos);
  EXPECT_EQ(dit::encode(viewOf(bgr, "32FC1"), jpeg(90)).error, dit::EncodeError::kUnsupportedEncoding);
  r = dit::encode(viewOf(scene(CV_16UC1), "mono16"), jpeg(90));
  EXPECT_EQ(r.error, dit::EncodeError::kUnsupportedEncoding);
  EXPECT_NE(r.reason.find("png"), std::string::npos);

  dit::ImageView v = viewOf(bgr, "bgr8");
  v.step = 3 * bgr.cols - 1;
  EXPECT_EQ(dit::encode(v, jpeg(90)).error, dit::EncodeError::kWrongSize);
  v = viewOf(bgr, "bgr8");
  v.size -= 1;
  EXPECT_EQ(dit::encode(v, jpeg(90)).error, dit::EncodeError::kWrongSize);
  v = viewOf(bgr, "mono8");  // claims fewer bytes per row than it has: allowed (step > row)
  EXPECT_TRUE(dit::encode(v, jpeg(90)).ok());
  v = viewOf(bgr, "bgr8");
  v.width = 0;
  EXPECT_EQ(dit::encode(v, jpeg(90)).error, dit::EncodeError::kWrongSize);
  v = viewOf(bgr, "bgr8");
  v.data = nullptr;
  EXPECT_EQ(dit::encode(v, jpeg(90)).error, dit::EncodeError::kWrongSize);
}

TEST(Codec, SettingsAreValidated) {
  EXPECT_TRUE(dit::validateSettings(jpeg(1)).empty());
  EXPECT_TRUE(dit::validateSettings(jpeg(100)).empty());
  for (int bad : {0, 101, -5}) {
    const auto reasons = dit::validateSettings(jpeg(bad));
    ASSERT_EQ(reasons.size(), 1u);
    EXPECT_NE(reasons[0].find("jpeg_quality"), std::string::npos);
    EXPECT_EQ(dit::encode(viewOf(scene(CV_8UC1), "mono8"), jpeg(bad)).error, dit::EncodeError::kBadSettings);
  }
  EXPECT_TRUE(dit::validateSettings(png(0)).empty());
  EXPECT_TRUE(dit::validateSettings(png(9)).empty());
  const auto reasons = dit::validateSettings(png(10));
  ASSERT_EQ(reasons.size(), 1u);
  EXPECT_NE(reasons[0].find("png_level"), std::string::npos);
  dit::Codec codec;
  EXPECT_TRUE(dit::parseCodec("jpeg", &codec) && codec == dit::Codec::kJpeg);
  EXPECT_TRUE(dit::parseCodec("png", &codec) && codec == dit::Codec::kPng);
  EXPECT_FALSE(dit::parseCodec("JPEG", &codec));
  EXPECT_FALSE(dit::parseCodec("tiff", &codec));
}

TEST(Codec, EmptyDataIsAnError) {
  const std::uint8_t byte = 0;
  EXPECT_EQ(dit::decode("bgr8; jpeg compressed bgr8", nullptr, 0).error, dit::DecodeError::kEmpty);
  EXPECT_EQ(dit::decode("bgr8; jpeg compressed bgr8", &byte, 0).error, dit::DecodeError::kEmpty);
}

TEST(Codec, TruncatedStreamsAreErrors) {
  for (const dit::EncodeSettings& s : {jpeg(90), png()}) {
    const dit::EncodeResult e = dit::encode(viewOf(scene(CV_8UC3), "bgr8"), s);
    ASSERT_TRUE(e.ok());
    for (double fraction : {0.99, 0.5, 0.1}) {
      const std::size_t n = static_cast<std::size_t>(fraction * e.data.size());
      const dit::DecodeResult d = dit::decode(e.format, e.data.data(), n);
      EXPECT_EQ(d.error, dit::DecodeError::kCorrupt) << e.format << " cut to " << n << " bytes";
      EXPECT_FALSE(d.reason.empty());
    }
  }
}

TEST(Codec, GarbageAndMislabelledStreamsAreErrors) {
  std::vector<std::uint8_t> garbage(5000);
  cv::RNG rng(7);
  for (auto& b : garbage) b = static_cast<std::uint8_t>(rng.uniform(0, 256));
  EXPECT_EQ(dit::decode("bgr8; jpeg compressed bgr8", garbage.data(), garbage.size()).error, dit::DecodeError::kCorrupt);
  EXPECT_EQ(dit::decode("mono8; png compressed ", garbage.data(), garbage.size()).error, dit::DecodeError::kCorrupt);

  // Valid markers around garbage: passes the completeness check, the decoder must refuse it.
  std::vector<std::uint8_t> fake = {0xFF, 0xD8, 0xFF};
  fake.insert(fake.end(), garbage.begin(), garbage.end());
  fake.push_back(0xFF);
  fake.push_back(0xD9);
  EXPECT_EQ(dit::decode("bgr8; jpeg compressed bgr8", fake.data(), fake.size()).error, dit::DecodeError::kCorrupt);

  // A PNG announced as JPEG.
  const dit::EncodeResult p = dit::encode(viewOf(scene(CV_8UC3), "bgr8"), png());
  EXPECT_EQ(dit::decode("bgr8; jpeg compressed bgr8", p.data.data(), p.data.size()).error, dit::DecodeError::kCorrupt);
  // A grey stream announced as colour.
  const dit::EncodeResult g = dit::encode(viewOf(scene(CV_8UC1), "mono8"), png());
  EXPECT_EQ(dit::decode("bgr8; png compressed bgr8", g.data.data(), g.data.size()).error,
            dit::DecodeError::kShapeMismatch);
}

TEST(Codec, BadFormatStringsAreErrors) {
  const dit::EncodeResult e = dit::encode(viewOf(scene(CV_8UC1), "mono8"), png());
  const auto decodeAs = [&](const std::string& format) { return dit::decode(format, e.data.data(), e.data.size()).error; };
  EXPECT_EQ(decodeAs(""), dit::DecodeError::kBadFormat);
  EXPECT_EQ(decodeAs("gif"), dit::DecodeError::kBadFormat);
  EXPECT_EQ(decodeAs("mono8; gif compressed "), dit::DecodeError::kBadFormat);
  EXPECT_EQ(decodeAs("mono8; png"), dit::DecodeError::kBadFormat);
  EXPECT_EQ(decodeAs("32FC1; compressedDepth png"), dit::DecodeError::kUnsupportedEncoding);
  EXPECT_EQ(decodeAs("bayer_rggb8; png compressed "), dit::DecodeError::kUnsupportedEncoding);
  EXPECT_EQ(decodeAs("mono8; png compressed "), dit::DecodeError::kNone);
}

TEST(Codec, DamagedStreamsNeverThrow) {
  // Random byte flips and cuts of valid streams: every outcome must be an error code or an image of the
  // original size and encoding, never an exception. (JPEG damage inside the entropy-coded data can
  // decode into a damaged picture; libjpeg cannot tell.)
  cv::RNG rng(2024);
  for (const dit::EncodeSettings& s : {jpeg(80), png()}) {
    const cv::Mat in = scene(CV_8UC3);
    const dit::EncodeResult e = dit::encode(viewOf(in, "bgr8"), s);
    ASSERT_TRUE(e.ok());
    int errors = 0;
    for (int trial = 0; trial < 200; ++trial) {
      std::vector<std::uint8_t> damaged = e.data;
      const int flips = rng.uniform(1, 20);
      for (int k = 0; k < flips; ++k)
        damaged[static_cast<std::size_t>(rng.uniform(0, static_cast<int>(damaged.size())))] ^=
            static_cast<std::uint8_t>(rng.uniform(1, 256));
      if (trial % 2 == 1) damaged.resize(static_cast<std::size_t>(rng.uniform(1, static_cast<int>(damaged.size()))));
      dit::DecodeResult d;
      ASSERT_NO_THROW(d = dit::decode(e.format, damaged.data(), damaged.size()));
      if (d.ok()) {
        EXPECT_EQ(d.image.encoding, "bgr8");
        EXPECT_EQ(d.image.data.size(), d.image.step * static_cast<std::size_t>(d.image.height));
      } else {
        ++errors;
      }
    }
    EXPECT_GE(errors, 100) << e.format << ": every cut stream at least must be refused";
  }
}

TEST(Codec, EncodeLeavesTheInputUntouched) {
  // rgb8 is converted to BGR for the encoder: into a copy, never into the caller's (const) buffer.
  for (const Case& c : kEightBit) {
    const cv::Mat in = scene(c.type);
    const cv::Mat before = in.clone();
    for (const dit::EncodeSettings& s : {jpeg(90), png()}) ASSERT_TRUE(dit::encode(viewOf(in, c.encoding), s).ok());
    EXPECT_EQ(cv::norm(in, before, cv::NORM_INF), 0.0) << c.encoding;
  }
}
