// The target mockup as rviz primitives, from its URDF (target_description, which docking_description's
// make_urdf.py writes from config/target.yaml: the one home of its geometry). The markers node draws them
// at the fused estimate only while it claims an orientation: before that the stack knows the position
// alone, shown by the estimate's ellipsoid, and rviz's own RobotModel would draw the mockup at the fixed
// frame's origin for want of a `target` frame. ROS-free (urdfdom).
#pragma once

#include <Eigen/Geometry>

#include <string>
#include <vector>

#include "docking_viz/palette.h"

namespace docking_viz {

struct MockupPart {
  enum class Shape { kBox, kCylinder, kSphere };
  Shape shape{Shape::kBox};
  Eigen::Isometry3d root_T_part{Eigen::Isometry3d::Identity()};  ///< in the URDF's root link (the port)
  /// As rviz's Marker scale: box edges; cylinder diameter, diameter, length (along its z); sphere diameter x 3.
  Eigen::Vector3d scale{Eigen::Vector3d::Zero()};
  Rgba colour;
};

/// Every visual of the URDF, placed in its root link's frame through its fixed joints. Throws
/// std::invalid_argument saying what is wrong: not a URDF, a joint that is not fixed (the mockup is one
/// rigid body), a mesh (not drawn as a primitive).
std::vector<MockupPart> mockupFromUrdf(const std::string& urdf_xml);

}  // namespace docking_viz
