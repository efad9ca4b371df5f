// What an image must satisfy before image_proc (debayer, rectify) or cv_bridge sees it (ROS-free). Debian's
// image_proc nodelets throw on an unknown encoding, a 0x0 image or data shorter than step * height, and
// an exception in a nodelet callback ends the whole perception manager (issue 12, item 1).
#pragma once

#include <array>
#include <cstdint>
#include <optional>
#include <string>
#include <vector>

#include "docking_perception/image_guard/image_guard_settings.h"

namespace docking_perception {
namespace image_guard {

/// Why an image is dropped, as a code (programs key on it; imageProblemName() is for people).
enum class ImageProblem : std::uint8_t {
  kNone = 0,
  kUnknownEncoding = 1,  ///< not one of the encodings image_proc's debayer and cv_bridge convert
  kZeroSize = 2,         ///< width or height is 0
  kTooLarge = 3,         ///< width or height above max_image_side_px
  kStepTooSmall = 4,     ///< step < width * bytes per pixel
  kDataSizeMismatch = 5, ///< data.size() != step * height (truncated, or padded)
  kBadEndianFlag = 6,    ///< is_bigendian neither 0 nor 1
  kNoFrameId = 7,        ///< header.frame_id empty: nothing downstream could place the image
  kStampNotFinite = 8,
  kStampInFuture = 9,    ///< more than max_future_stamp_s ahead of now
  kStepNotAligned = 10,  ///< step not a multiple of one channel's size (a 16-bit image with an odd step):
                         ///< cv::Mat refuses it with an exception that aborted the manager
  kBigEndian16Bit = 11,  ///< is_bigendian set on a 16-bit encoding: cv_bridge's byte swap hands debayer's
                         ///< cvtColor a wrong channel count (rgba16, bayer_*16), which aborted the manager.
                         ///< No camera we know sends big-endian; 8-bit images ignore the flag.
};
constexpr std::size_t kImageProblemCount = 12;
const char* imageProblemName(ImageProblem problem);

/// The parts of a sensor_msgs/Image that are checked (the pixels are not read).
struct ImageFacts {
  std::string encoding;
  std::uint32_t width{0};
  std::uint32_t height{0};
  std::uint32_t step{0};
  std::uint64_t data_size{0};
  std::uint8_t is_bigendian{0};
  std::string frame_id;
  double stamp_s{0.0};
};

// ImageLimits, the checks' settings, is declared in settings/image_guard.yaml (generated header).

/// Throws std::invalid_argument (ConfigError) naming the first setting its declaration does not allow.
void validate(const ImageLimits& limits);

/// Bytes per pixel of an encoding image_proc and cv_bridge convert; 0 for any other.
std::uint32_t bytesPerPixel(const std::string& encoding);

/// The first problem found, in the order of the enum (cheap checks first; the pixels are not read).
ImageProblem checkImage(const ImageFacts& image, double now_s, const ImageLimits& limits);

/// The size of an image that passed, for checking a camera_info against it.
struct ImageSize {
  std::uint32_t width{0};
  std::uint32_t height{0};
};

/// Why a camera_info is dropped, as a code (cameraInfoProblemName() is for people). image_proc's rectify,
/// stereo_image_proc and our estimators build maps and models from it; a malformed one (1 x 100000 px)
/// aborted the perception manager inside cv::remap (issue 12).
enum class CameraInfoProblem : std::uint8_t {
  kNone = 0,
  kZeroSize = 1,                 ///< width or height 0
  kTooLarge = 2,                 ///< width or height above max_image_side_px
  kBadBinningOrRoi = 3,          ///< binning above kMaxBinning, or a ROI outside the sensor
  kSizeDiffersFromImage = 4,     ///< the sensor size (after ROI and binning) is not the last image's size
  kUnknownDistortionModel = 5,   ///< not plumb_bob, rational_polynomial or equidistant
  kDistortionCountMismatch = 6,  ///< D has neither 0 nor the model's number of coefficients
  kNotFinite = 7,                ///< a NaN or infinity in D, K, R or P
  kUncalibrated = 8,             ///< K or P without positive focal lengths (an uncalibrated camera)
  kRectificationNotRotation = 9, ///< R is not a rotation (R R^T != I or det != 1, within kRotationTolerance)
  kNoFrameId = 10,
  kStampInFuture = 11,           ///< more than max_future_stamp_s ahead of now
  kNoImageYet = 12,              ///< no image of this camera has passed yet: the size cannot be checked
};
constexpr std::size_t kCameraInfoProblemCount = 13;
const char* cameraInfoProblemName(CameraInfoProblem problem);

/// Binning above this is not a camera of ours (image_proc reduces the maps by it).
constexpr std::uint32_t kMaxBinning = 8;
/// Tolerance of R's orthonormality: calibration files keep 6-9 digits.
constexpr double kRotationTolerance = 1e-3;

/// The parts of a sensor_msgs/CameraInfo that are checked.
struct CameraInfoFacts {
  std::uint32_t width{0};
  std::uint32_t height{0};
  std::uint32_t binning_x{0};
  std::uint32_t binning_y{0};
  std::uint32_t roi_x_offset{0};
  std::uint32_t roi_y_offset{0};
  std::uint32_t roi_width{0};   ///< 0 (with roi_height 0): the full sensor
  std::uint32_t roi_height{0};
  std::string distortion_model;
  std::vector<double> D;
  std::array<double, 9> K{};
  std::array<double, 9> R{};
  std::array<double, 12> P{};
  std::string frame_id;
  double stamp_s{0.0};
};

/// The image size a camera_info describes: the ROI (or the whole sensor), divided by the binning.
ImageSize describedImageSize(const CameraInfoFacts& info);

/// The first problem found. `last_image`: the size of this camera's last image that passed the guard;
/// without one the size agreement cannot be checked yet: kNoImageYet (consumers pair an info with its
/// image by stamp, so an info that comes before any image is of no use to them anyway).
CameraInfoProblem checkCameraInfo(const CameraInfoFacts& info, const std::optional<ImageSize>& last_image,
                                  double now_s, const ImageLimits& limits);

}  // namespace image_guard
}  // namespace docking_perception
