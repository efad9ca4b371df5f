#include "docking_viz/target_mockup.h"

#include <stdexcept>

#include <urdf_parser/urdf_parser.h>

namespace docking_viz {
namespace {

Eigen::Isometry3d toIsometry(const urdf::Pose& pose) {
  Eigen::Isometry3d t = Eigen::Isometry3d::Identity();
  t.translation() << pose.position.x, pose.position.y, pose.position.z;
  t.linear() = Eigen::Quaterniond(pose.rotation.w, pose.rotation.x, pose.rotation.y, pose.rotation.z)
                   .normalized()
                   .toRotationMatrix();
  return t;
}

MockupPart partOf(const urdf::Visual& visual, const Eigen::Isometry3d& root_T_link, const std::string& link) {
  MockupPart part;
  part.root_T_part = root_T_link * toIsometry(visual.origin);
  if (visual.material) {
    const urdf::Color& c = visual.material->color;
    part.colour = Rgba{c.r, c.g, c.b, c.a};
  }
  switch (visual.geometry ? visual.geometry->type : urdf::Geometry::MESH) {
    case urdf::Geometry::BOX: {
      const auto& box = static_cast<const urdf::Box&>(*visual.geometry);
      part.scale << box.dim.x, box.dim.y, box.dim.z;
      return part;
    }
    case urdf::Geometry::CYLINDER: {
      const auto& cylinder = static_cast<const urdf::Cylinder&>(*visual.geometry);
      part.shape = MockupPart::Shape::kCylinder;
      part.scale << 2.0 * cylinder.radius, 2.0 * cylinder.radius, cylinder.length;
      return part;
    }
    case urdf::Geometry::SPHERE: {
      const auto& sphere = static_cast<const urdf::Sphere&>(*visual.geometry);
      part.shape = MockupPart::Shape::kSphere;
      part.scale = Eigen::Vector3d::Constant(2.0 * sphere.radius);
      return part;
    }
    default:
      throw std::invalid_argument("link '" + link + "' has a visual that is not a box, cylinder or sphere");
  }
}

void addLink(const urdf::Link& link, const Eigen::Isometry3d& root_T_link, std::vector<MockupPart>* parts) {
  for (const auto& visual : link.visual_array) {
    if (visual) parts->push_back(partOf(*visual, root_T_link, link.name));
  }
  for (const auto& joint : link.child_joints) {
    if (joint->type != urdf::Joint::FIXED) {
      throw std::invalid_argument("joint '" + joint->name + "' is not fixed: the mockup must be one rigid body");
    }
    for (const auto& child : link.child_links) {
      if (child->name == joint->child_link_name) {
        addLink(*child, root_T_link * toIsometry(joint->parent_to_joint_origin_transform), parts);
      }
    }
  }
}

}  // namespace

std::vector<MockupPart> mockupFromUrdf(const std::string& urdf_xml) {
  const urdf::ModelInterfaceSharedPtr model = urdf::parseURDF(urdf_xml);
  if (!model || !model->getRoot()) throw std::invalid_argument("not a URDF with a root link");
  std::vector<MockupPart> parts;
  addLink(*model->getRoot(), Eigen::Isometry3d::Identity(), &parts);
  return parts;
}

}  // namespace docking_viz
