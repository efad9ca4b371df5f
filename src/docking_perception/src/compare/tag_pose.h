// AprilTag 3 for the comparison tools: the tagged target variant (config/target_tagged.yaml,
// `target.apriltag`) and its face texture. The detector and the tag frame live in the mono core
// (docking_perception/mono/apriltag_pose.h), shared with the inner pattern. ROS-free.
#pragma once

#include <opencv2/core.hpp>
#include <string>

#include "docking_perception/mono/apriltag_pose.h"

namespace docking_perception {
namespace compare {

using mono::cameraTTargetFromTag;
using mono::TagDetector;
using mono::TagError;
using mono::TagResult;
using mono::TagSpec;
using mono::tagCells;
using mono::targetTTag;

// Reads `target.apriltag` of a target yaml. Throws TagError naming the file and the field.
TagSpec loadTagSpec(const std::string& target_yaml);

// The face texture with the tag: grey, face_width_m x face_height_m at px_per_m, white (`paper`)
// around the tag; the tag's cells (its own white border ring included) from apriltag_to_image.
cv::Mat makeTagTexture(const TagSpec& spec, double face_width_m, double face_height_m, double px_per_m,
                       int black = 25, int paper = 240);

}  // namespace compare
}  // namespace docking_perception
