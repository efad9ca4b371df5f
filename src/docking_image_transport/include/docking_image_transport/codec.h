// The image codec of the `compressed` transport, without ROS: a raw image (the fields of
// sensor_msgs/Image) to JPEG or PNG bytes plus the `format` string of sensor_msgs/CompressedImage, and
// back. The format string follows the standard compressed transport's convention,
// "<encoding>; <jpeg|png> compressed <target>", where <target> is "bgr8" for colour images and empty for
// grey ones ("mono8; png compressed "), so that standard tools read our messages and we read theirs.
//
// Supported: mono8, bgr8, rgb8 (JPEG and PNG), mono16 (PNG only: JPEG is 8-bit). Nothing here throws:
// every failure is an error code plus a human-readable reason for the log.
#pragma once

#include <cstddef>
#include <cstdint>
#include <string>
#include <vector>

namespace docking_image_transport {

enum class Codec { kJpeg, kPng };

// "jpeg" / "png"; false for anything else (case-sensitive, as the parameter is documented).
bool parseCodec(const std::string& name, Codec* codec);
const char* codecName(Codec codec);

struct EncodeSettings {
  Codec codec = Codec::kJpeg;
  int jpeg_quality = 90;  // 1..100
  int png_level = 3;      // 0..9 (zlib); above ~3 costs much CPU for little size on camera images
};

// One reason per invalid field ("jpeg_quality must be in 1..100 (got 0)"); empty: usable.
std::vector<std::string> validateSettings(const EncodeSettings& settings);

// Read-only view of a raw image: the fields of sensor_msgs/Image, data not copied.
struct ImageView {
  int width = 0;
  int height = 0;
  std::string encoding;
  bool is_bigendian = false;  // only matters for mono16
  std::size_t step = 0;       // bytes per row, >= width * bytes per pixel
  const std::uint8_t* data = nullptr;
  std::size_t size = 0;       // bytes available at data, >= step * height
};

// A decoded image, rows packed (step = width * bytes per pixel), little-endian.
struct Image {
  int width = 0;
  int height = 0;
  std::string encoding;
  std::size_t step = 0;
  std::vector<std::uint8_t> data;
};

enum class EncodeError {
  kNone = 0,
  kBadSettings,           // validateSettings() complained
  kUnsupportedEncoding,   // e.g. bayer_rggb8, 32FC1, or mono16 with JPEG
  kWrongSize,             // width/height not positive, step too small, or fewer bytes than step * height
  kEncoderFailed,         // OpenCV refused (should not happen for supported input)
};

enum class DecodeError {
  kNone = 0,
  kEmpty,                 // no bytes
  kBadFormat,             // format string not "<encoding>; jpeg|png compressed ..." nor "jpeg"/"png"
  kUnsupportedEncoding,   // format names an encoding we do not decode (e.g. compressedDepth, bayer)
  kCorrupt,               // not a JPEG/PNG stream, truncated, or the decoder failed
  kShapeMismatch,         // decoded channels / depth do not fit the encoding the format names
};

const char* errorName(EncodeError error);
const char* errorName(DecodeError error);

struct EncodeResult {
  EncodeError error = EncodeError::kNone;
  std::string reason;                // empty when error == kNone
  std::string format;                // the CompressedImage format string
  std::vector<std::uint8_t> data;    // the JPEG / PNG stream
  bool ok() const { return error == EncodeError::kNone; }
};

struct DecodeResult {
  DecodeError error = DecodeError::kNone;
  std::string reason;
  Image image;
  bool ok() const { return error == DecodeError::kNone; }
};

EncodeResult encode(const ImageView& image, const EncodeSettings& settings);
DecodeResult decode(const std::string& format, const std::uint8_t* data, std::size_t size);

}  // namespace docking_image_transport
