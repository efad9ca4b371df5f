// What a capture source string means: a V4L2 device (index or /dev path), a video file or stream, or an
// image-sequence pattern. ROS-free.
#pragma once

#include <string>

namespace docking_perception {
namespace camera {

enum class SourceKind {
  kDeviceIndex,     // "0": /dev/video0 through V4L2
  kDevicePath,      // "/dev/video2", "/dev/v4l/by-id/usb-...": V4L2
  kVideoFile,       // a file or stream URL that OpenCV's FFmpeg backend reads
  kImageSequence,   // "/data/left_%04d.png": numbered images (printf integer pattern)
};

struct SourceSpec {
  SourceKind kind = SourceKind::kVideoFile;
  std::string text;       // the source as configured (trimmed)
  int device_index = -1;  // kDeviceIndex only

  // A live device: it can be unplugged and come back; a file or sequence ends instead.
  bool isLiveDevice() const { return kind == SourceKind::kDeviceIndex || kind == SourceKind::kDevicePath; }
  // For messages: "V4L2 device /dev/video0", "image sequence /x/left_%04d.png", ...
  std::string describe() const;
};

// Parses a configured source. Throws std::invalid_argument (saying what is wrong with `text`) for an
// empty string, a negative or out-of-range index, or a '%' that is not one printf integer conversion.
SourceSpec parseSourceSpec(const std::string& text);

const char* toString(SourceKind kind);

}  // namespace camera
}  // namespace docking_perception
