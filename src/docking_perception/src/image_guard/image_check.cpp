#include "docking_perception/image_guard/image_check.h"

#include <algorithm>
#include <cmath>
#include <optional>
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
    case ImageProblem::kBigEndian16Bit:
      return "big_endian_16_bit";
  }
  return "unknown";
}

const char* cameraInfoProblemName(CameraInfoProblem problem) {
  switch (problem) {
    case CameraInfoProblem::kNone:
      return "none";
    case CameraInfoProblem::kZeroSize:
      return "zero_size";
    case CameraInfoProblem::kTooLarge:
      return "too_large";
    case CameraInfoProblem::kBadBinningOrRoi:
      return "bad_binning_or_roi";
    case CameraInfoProblem::kSizeDiffersFromImage:
      return "size_differs_from_image";
    case CameraInfoProblem::kUnknownDistortionModel:
      return "unknown_distortion_model";
    case CameraInfoProblem::kDistortionCountMismatch:
      return "distortion_count_mismatch";
    case CameraInfoProblem::kNotFinite:
      return "not_finite";
    case CameraInfoProblem::kUncalibrated:
      return "uncalibrated";
    case CameraInfoProblem::kRectificationNotRotation:
      return "rectification_not_rotation";
    case CameraInfoProblem::kNoFrameId:
      return "no_frame_id";
    case CameraInfoProblem::kStampInFuture:
      return "stamp_in_future";
    case CameraInfoProblem::kNoImageYet:
      return "no_image_yet";
  }
  return "unknown";
}

void validate(const ImageLimits& limits) { docking_settings::validateSettings(limits); }

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
  const auto max_side = static_cast<std::uint32_t>(limits.max_image_side_px);
  if (std::max(image.width, image.height) > max_side) return ImageProblem::kTooLarge;
  // 64-bit products: a forged width and step must not overflow into a match.
  if (static_cast<std::uint64_t>(image.step) < static_cast<std::uint64_t>(image.width) * bytes_per_pixel) {
    return ImageProblem::kStepTooSmall;
  }
  if (image.step % pixelLayout(image.encoding)->bytes_per_channel != 0) return ImageProblem::kStepNotAligned;
  if (image.data_size != static_cast<std::uint64_t>(image.step) * image.height) return ImageProblem::kDataSizeMismatch;
  if (image.is_bigendian > 1) return ImageProblem::kBadEndianFlag;
  if (image.is_bigendian == 1 && pixelLayout(image.encoding)->bytes_per_channel > 1) {
    return ImageProblem::kBigEndian16Bit;
  }
  if (image.frame_id.empty()) return ImageProblem::kNoFrameId;
  if (!std::isfinite(image.stamp_s)) return ImageProblem::kStampNotFinite;
  if (image.stamp_s - now_s > limits.max_future_stamp_s) return ImageProblem::kStampInFuture;
  return ImageProblem::kNone;
}

namespace {
/// Coefficients of each distortion model image_geometry knows (sensor_msgs/distortion_models.h).
std::optional<std::size_t> distortionCount(const std::string& model) {
  if (model == "plumb_bob") return 5;
  if (model == "rational_polynomial") return 8;
  if (model == "equidistant") return 4;
  return std::nullopt;
}

template <typename Values>
bool allFinite(const Values& values) {
  for (double v : values) {
    if (!std::isfinite(v)) return false;
  }
  return true;
}

bool isRotation(const std::array<double, 9>& r) {
  for (int i = 0; i < 3; ++i) {
    for (int j = 0; j < 3; ++j) {
      const double dot = r[3 * i] * r[3 * j] + r[3 * i + 1] * r[3 * j + 1] + r[3 * i + 2] * r[3 * j + 2];
      if (std::abs(dot - (i == j ? 1.0 : 0.0)) > kRotationTolerance) return false;
    }
  }
  const double det = r[0] * (r[4] * r[8] - r[5] * r[7]) - r[1] * (r[3] * r[8] - r[5] * r[6]) +
                     r[2] * (r[3] * r[7] - r[4] * r[6]);
  return std::abs(det - 1.0) <= kRotationTolerance;
}

bool roiInsideSensor(const CameraInfoFacts& info) {
  if (info.roi_width == 0 && info.roi_height == 0) return info.roi_x_offset == 0 && info.roi_y_offset == 0;
  if (info.roi_width == 0 || info.roi_height == 0) return false;
  return static_cast<std::uint64_t>(info.roi_x_offset) + info.roi_width <= info.width &&
         static_cast<std::uint64_t>(info.roi_y_offset) + info.roi_height <= info.height;
}
}  // namespace

ImageSize describedImageSize(const CameraInfoFacts& info) {
  const bool full = info.roi_width == 0 && info.roi_height == 0;
  ImageSize size;
  size.width = (full ? info.width : info.roi_width) / std::max<std::uint32_t>(info.binning_x, 1);
  size.height = (full ? info.height : info.roi_height) / std::max<std::uint32_t>(info.binning_y, 1);
  return size;
}

CameraInfoProblem checkCameraInfo(const CameraInfoFacts& info, const std::optional<ImageSize>& last_image,
                                  double now_s, const ImageLimits& limits) {
  if (info.width == 0 || info.height == 0) return CameraInfoProblem::kZeroSize;
  const auto max_side = static_cast<std::uint32_t>(limits.max_image_side_px);
  if (std::max(info.width, info.height) > max_side) return CameraInfoProblem::kTooLarge;
  if (info.binning_x > kMaxBinning || info.binning_y > kMaxBinning || !roiInsideSensor(info)) {
    return CameraInfoProblem::kBadBinningOrRoi;
  }
  const ImageSize described = describedImageSize(info);
  if (!last_image) return CameraInfoProblem::kNoImageYet;
  if (described.width != last_image->width || described.height != last_image->height) {
    return CameraInfoProblem::kSizeDiffersFromImage;
  }
  const std::optional<std::size_t> count = distortionCount(info.distortion_model);
  if (!count) return CameraInfoProblem::kUnknownDistortionModel;
  if (!info.D.empty() && info.D.size() != *count) return CameraInfoProblem::kDistortionCountMismatch;
  if (!allFinite(info.D) || !allFinite(info.K) || !allFinite(info.R) || !allFinite(info.P)) {
    return CameraInfoProblem::kNotFinite;
  }
  if (!(info.K[0] > 0.0 && info.K[4] > 0.0 && info.P[0] > 0.0 && info.P[5] > 0.0)) {
    return CameraInfoProblem::kUncalibrated;
  }
  if (!isRotation(info.R)) return CameraInfoProblem::kRectificationNotRotation;
  if (info.frame_id.empty()) return CameraInfoProblem::kNoFrameId;
  if (!std::isfinite(info.stamp_s) || info.stamp_s - now_s > limits.max_future_stamp_s) {
    return CameraInfoProblem::kStampInFuture;
  }
  return CameraInfoProblem::kNone;
}

}  // namespace image_guard
}  // namespace docking_perception
