// AprilTag 3 (Debian's libapriltag) in the mono core: a tag36h11 tag printed on the face (plane x = 0 of
// frame `target`), its detection with apriltag's own pose estimation (estimate_tag_pose) and the pose of
// frame `target` derived from the tag's pose. Used by the inner pattern (InnerPatternDetector) and by the
// comparison tools (src/compare/tag_pose.h). ROS-free.
#pragma once

#include <Eigen/Geometry>
#include <array>
#include <opencv2/core.hpp>
#include <stdexcept>
#include <string>

#include "docking_perception/mono/pose_types.h"

struct apriltag_detector;
struct apriltag_family;

namespace docking_perception {
namespace mono {

// The tag on the face (plane x = 0 of frame `target`), printed upright: its image rows run along -z
// and its columns along +y, as the face texture's.
struct TagSpec {
  std::string family = "tag36h11";
  int id = 0;
  double size_m = 0.0;                                   // apriltag's tagsize: the black square's edge
  Eigen::Vector3d center_m = Eigen::Vector3d::Zero();    // in frame `target`, x = 0
};

class TagError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

// Pose of apriltag's tag frame in frame `target`. apriltag's tag frame: origin at the tag centre,
// x to the right and y down as the tag is seen printed, z into the tag. The face's viewer sees +y of
// `target` to the right and +z up, and looks along -x, so x_tag = y_target, y_tag = -z_target,
// z_tag = -x_target.
Eigen::Isometry3d targetTTag(const TagSpec& spec);

// camera <- target from apriltag's camera <- tag.
Eigen::Isometry3d cameraTTargetFromTag(const Eigen::Isometry3d& camera_T_tag, const TagSpec& spec);

// The black square's corners in frame `target`, in apriltag's order of detection->p (tag frame
// (-1, 1), (1, 1), (1, -1), (-1, -1) times size/2).
std::array<Eigen::Vector3d, 4> tagCornersInTarget(const TagSpec& spec);

// The tag's print, one pixel per cell, its white ring included (10 x 10 for tag36h11): 0 black, 255
// white; rows along -z, columns along +y of frame `target` (apriltag_to_image).
cv::Mat tagCells(const TagSpec& spec);

struct TagResult {
  bool found = false;
  std::string status;                 // why not found
  int detections = 0;                 // tags of the family found (any id)
  Eigen::Isometry3d camera_T_target = Eigen::Isometry3d::Identity();
  double object_space_error = 0.0;    // estimate_tag_pose's error of the chosen solution
  double decision_margin = 0.0;
  int hamming = 0;
  // The black square's corners, px (OpenCV convention: pixel centres at integer coordinates), in the
  // order of tagCornersInTarget.
  std::array<Eigen::Vector2d, 4> corners_px{};
  double processing_time_ms = 0.0;    // thread CPU time of detection + pose
};

// What TagDetector::detect computes beyond the detection: apriltag's own pose (estimate_tag_pose, a
// third of the cost of a search in a small region), or the corners only, for a caller that fits its own
// pose (the inner pattern fits the grid corners inside the tag).
enum class TagOutput { kCornersAndPose, kCornersOnly };

// tag36h11 detector (one thread unless told), AprilTag's defaults otherwise.
class TagDetector {
 public:
  TagDetector(const TagSpec& spec, int nthreads = 1, double quad_decimate = 2.0);
  ~TagDetector();
  TagDetector(const TagDetector&) = delete;
  TagDetector& operator=(const TagDetector&) = delete;

  // gray: 8-bit single channel, rectified, described by camera. roi: where to look (empty: the whole
  // image); corners and pose are in the full image's pixels. kCornersOnly: camera_T_target stays the
  // identity and object_space_error 0.
  TagResult detect(const cv::Mat& gray, const CameraIntrinsics& camera, const cv::Rect& roi = cv::Rect(),
                   TagOutput output = TagOutput::kCornersAndPose);

 private:
  TagSpec spec_;
  apriltag_family* family_ = nullptr;
  apriltag_detector* detector_ = nullptr;
};

}  // namespace mono
}  // namespace docking_perception
