#include "docking_perception/image_guard/image_check.h"

#include <cmath>
#include <stdexcept>
#include <unordered_map>

namespace docking_perception {
namespace image_guard {

const char* imageProblemName(ImageProblem problem) {
  switch (problem) {
    case ImageProblem::kNone:
      return "none";
    case ImageProblem::kUnknownEncoding:
      return "unknown_encoding";
    case ImageProblem::kZeroSize:
      return "zero_size";
    case ImageProblem::kTooLarge:
      return "too_large";
    case ImageProblem::kStepTooSmall:
      return "step_too_small";
    case ImageProblem::kStepNotAligned:
      return "step_not_aligned";
    case ImageProblem::kDataSizeMismatch:
      return "data_size_mismatch";
    case ImageProblem::kBadEndianFlag:
      return "bad_endian_flag";
    case ImageProblem::kNoFrameId:
      return "no_frame_id";
    case ImageProblem::kStampNotFinite:
      return "stamp_not_finite";
    case ImageProblem::kStampInFuture:
      return "stamp_in_future";
  }
  return "unknown";
}

void validate(const ImageLimits& limits) {
  if (limits.max_side_px == 0) throw std::invalid_argument("max_image_side_px must be positive");
  if (!std::isfinite(limits.max_future_stamp_s) || limits.max_future_stamp_s < 0.0) {
    throw std::invalid_argument("max_future_stamp_s must be a number >= 0");
  }
}

namespace {
struct PixelLayout {
  std::uint32_t bytes_per_pixel;
  std::uint32_t bytes_per_channel;  // a row must start on a whole channel (cv::Mat's esz1)
};

const PixelLayout* pixelLayout(const std::string& encoding) {
  // sensor_msgs/image_encodings.h names; image_proc's debayer takes mono, bayer, colour and yuv422.
  static const std::unordered_map<std::string, PixelLayout> kKnown = {
      {"mono8", {1, 1}},        {"mono16", {2, 2}},       {"bgr8", {3, 1}},         {"rgb8", {3, 1}},
      {"bgra8", {4, 1}},        {"rgba8", {4, 1}},        {"bgr16", {6, 2}},        {"rgb16", {6, 2}},
      {"bgra16", {8, 2}},       {"rgba16", {8, 2}},       {"bayer_rggb8", {1, 1}},  {"bayer_bggr8", {1, 1}},
      {"bayer_gbrg8", {1, 1}},  {"bayer_grbg8", {1, 1}},  {"bayer_rggb16", {2, 2}}, {"bayer_bggr16", {2, 2}},
      {"bayer_gbrg16", {2, 2}}, {"bayer_grbg16", {2, 2}}, {"yuv422", {2, 1}},
  };
  const auto it = kKnown.find(encoding);
  return it == kKnown.end() ? nullptr : &it->second;
}
}  // namespace

std::uint32_t bytesPerPixel(const std::string& encoding) {
  const PixelLayout* layout = pixelLayout(encoding);
  return layout ? layout->bytes_per_pixel : 0;
}

ImageProblem checkImage(const ImageFacts& image, double now_s, const ImageLimits& limits) {
  const std::uint32_t bytes_per_pixel = bytesPerPixel(image.encoding);
  if (bytes_per_pixel == 0) return ImageProblem::kUnknownEncoding;
  if (image.width == 0 || image.height == 0) return ImageProblem::kZeroSize;
  if (image.width > limits.max_side_px || image.height > limits.max_side_px) return ImageProblem::kTooLarge;
  // 64-bit products: a forged width and step must not overflow into a match.
  if (static_cast<std::uint64_t>(image.step) < static_cast<std::uint64_t>(image.width) * bytes_per_pixel) {
    return ImageProblem::kStepTooSmall;
  }
  if (image.step % pixelLayout(image.encoding)->bytes_per_channel != 0) return ImageProblem::kStepNotAligned;
  if (image.data_size != static_cast<std::uint64_t>(image.step) * image.height) return ImageProblem::kDataSizeMismatch;
  if (image.is_bigendian > 1) return ImageProblem::kBadEndianFlag;
  if (image.frame_id.empty()) return ImageProblem::kNoFrameId;
  if (!std::isfinite(image.stamp_s)) return ImageProblem::kStampNotFinite;
  if (image.stamp_s - now_s > limits.max_future_stamp_s) return ImageProblem::kStampInFuture;
  return ImageProblem::kNone;
}

}  // namespace image_guard
}  // namespace docking_perception
