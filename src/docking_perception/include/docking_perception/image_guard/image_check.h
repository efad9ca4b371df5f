// What an image must satisfy before image_proc (debayer, rectify) or cv_bridge sees it (ROS-free). Debian's
// image_proc nodelets throw on an unknown encoding, a 0x0 image or data shorter than step * height, and
// an exception in a nodelet callback ends the whole perception manager (issue 12, item 1).
#pragma once

#include <cstdint>
#include <string>

namespace docking_perception {
namespace image_guard {

/// Why an image is dropped, as a code (programs key on it; imageProblemName() is for people).
enum class ImageProblem : std::uint8_t {
  kNone = 0,
  kUnknownEncoding = 1,  ///< not one of the encodings image_proc's debayer and cv_bridge convert
  kZeroSize = 2,         ///< width or height is 0
  kTooLarge = 3,         ///< width or height above max_side_px
  kStepTooSmall = 4,     ///< step < width * bytes per pixel
  kDataSizeMismatch = 5, ///< data.size() != step * height (truncated, or padded)
  kBadEndianFlag = 6,    ///< is_bigendian neither 0 nor 1
  kNoFrameId = 7,        ///< header.frame_id empty: nothing downstream could place the image
  kStampNotFinite = 8,
  kStampInFuture = 9,    ///< more than max_future_stamp_s ahead of now
  kStepNotAligned = 10,  ///< step not a multiple of one channel's size (a 16-bit image with an odd step):
                         ///< cv::Mat refuses it with an exception that aborted the manager
};
constexpr std::size_t kImageProblemCount = 11;
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

struct ImageLimits {
  std::uint32_t max_side_px{8192};  ///< larger than any camera of ours by far; bounds step * height
  double max_future_stamp_s{0.5};   ///< clock skew between the camera computer and this one
};
/// Throws std::invalid_argument naming the bad parameter (max_image_side_px, max_future_stamp_s).
void validate(const ImageLimits& limits);

/// Bytes per pixel of an encoding image_proc and cv_bridge convert; 0 for any other.
std::uint32_t bytesPerPixel(const std::string& encoding);

/// The first problem found, in the order of the enum (cheap checks first; the pixels are not read).
ImageProblem checkImage(const ImageFacts& image, double now_s, const ImageLimits& limits);

}  // namespace image_guard
}  // namespace docking_perception
