// AprilTag 3 (Debian's libapriltag) as the peer of mono_pose: the tag the tagged target variant carries
// (config/target_tagged.yaml, `target.apriltag`), its detection with apriltag's own pose estimation
// (estimate_tag_pose), and the pose of frame `target` derived from the tag's pose. ROS-free.
#pragma once

#include <Eigen/Geometry>
#include <opencv2/core.hpp>
#include <stdexcept>
#include <string>

#include "docking_perception/mono/pose_types.h"

struct apriltag_detector;
struct apriltag_family;

namespace docking_perception {
namespace compare {

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

// Reads `target.apriltag` of a target yaml. Throws TagError naming the file and the field.
TagSpec loadTagSpec(const std::string& target_yaml);

// Pose of apriltag's tag frame in frame `target`. apriltag's tag frame: origin at the tag centre,
// x to the right and y down as the tag is seen printed, z into the tag. The face's viewer sees +y of
// `target` to the right and +z up, and looks along -x, so x_tag = y_target, y_tag = -z_target,
// z_tag = -x_target.
Eigen::Isometry3d targetTTag(const TagSpec& spec);

// camera <- target from apriltag's camera <- tag.
Eigen::Isometry3d cameraTTargetFromTag(const Eigen::Isometry3d& camera_T_tag, const TagSpec& spec);

// The face texture with the tag: grey, face_width_m x face_height_m at px_per_m, white (`paper`)
// around the tag; the tag's cells (its own white border ring included) from apriltag_to_image.
cv::Mat makeTagTexture(const TagSpec& spec, double face_width_m, double face_height_m, double px_per_m,
                       int black = 25, int paper = 240);

struct TagResult {
  bool found = false;
  std::string status;                 // why not found
  int detections = 0;                 // tags of the family found (any id)
  Eigen::Isometry3d camera_T_target = Eigen::Isometry3d::Identity();
  double object_space_error = 0.0;    // estimate_tag_pose's error of the chosen solution
  double decision_margin = 0.0;
  int hamming = 0;
  double processing_time_ms = 0.0;    // thread CPU time of detection + pose
};

// tag36h11 detector (one thread unless told), AprilTag's defaults otherwise.
class TagDetector {
 public:
  TagDetector(const TagSpec& spec, int nthreads = 1, double quad_decimate = 2.0);
  ~TagDetector();
  TagDetector(const TagDetector&) = delete;
  TagDetector& operator=(const TagDetector&) = delete;

  // gray: 8-bit single channel, rectified, described by camera.
  TagResult detect(const cv::Mat& gray, const mono::CameraIntrinsics& camera);

 private:
  TagSpec spec_;
  apriltag_family* family_ = nullptr;
  apriltag_detector* detector_ = nullptr;
};

}  // namespace compare
}  // namespace docking_perception
