// mockupFromUrdf: each visual placed in the root link through the fixed joints, scales as rviz's Marker
// wants them, colours kept; a moving joint or a mesh refused.
#include <gtest/gtest.h>

#include <cmath>
#include <stdexcept>
#include <string>

#include "docking_viz/target_mockup.h"

using namespace docking_viz;

namespace {

// The shape of make_urdf.py's target: the root link is the port; a body behind it on a fixed joint.
std::string urdf(const std::string& joint_type, const std::string& body_geometry) {
  return R"(<robot name="target">
  <material name="face"><color rgba="0.9 0.8 0.2 1"/></material>
  <link name="target">
    <visual><origin xyz="0 0 0" rpy="0 1.5707963267948966 0"/>
      <geometry><cylinder radius="0.03" length="0.002"/></geometry><material name="face"/></visual>
  </link>
  <link name="body">
    <visual><origin xyz="-0.15 0 0" rpy="0 0 0"/><geometry>)" + body_geometry + R"(</geometry></visual>
  </link>
  <joint name="port_to_body" type=")" + joint_type + R"(">
    <parent link="target"/><child link="body"/>
    <origin xyz="-0.01 0 -0.05" rpy="0 0 0"/><axis xyz="0 0 1"/><limit lower="0" upper="1" effort="1" velocity="1"/>
  </joint>
</robot>)";
}

}  // namespace

TEST(TargetMockup, VisualsPlacedThroughTheFixedJoints) {
  const std::vector<MockupPart> parts = mockupFromUrdf(urdf("fixed", R"(<box size="0.295 0.3 0.24"/>)"));
  ASSERT_EQ(parts.size(), 2U);
  const MockupPart& port = parts[0];
  EXPECT_EQ(port.shape, MockupPart::Shape::kCylinder);
  EXPECT_NEAR(port.scale.x(), 0.06, 1e-12);  // diameter
  EXPECT_NEAR(port.scale.z(), 0.002, 1e-12);  // length, along the cylinder's z...
  // ...which the visual's pitch of 90 deg turns onto the root's -x / +x axis (the port axis).
  EXPECT_NEAR(std::abs((port.root_T_part.linear() * Eigen::Vector3d::UnitZ()).x()), 1.0, 1e-9);
  EXPECT_NEAR(port.colour.r, 0.9F, 1e-6);
  const MockupPart& body = parts[1];
  EXPECT_EQ(body.shape, MockupPart::Shape::kBox);
  EXPECT_TRUE(body.scale.isApprox(Eigen::Vector3d(0.295, 0.3, 0.24)));
  // joint origin (-0.01, 0, -0.05) then the visual's (-0.15, 0, 0)
  EXPECT_TRUE(body.root_T_part.translation().isApprox(Eigen::Vector3d(-0.16, 0.0, -0.05), 1e-12))
      << body.root_T_part.translation().transpose();
}

TEST(TargetMockup, SphereScaleIsItsDiameter) {
  const std::vector<MockupPart> parts = mockupFromUrdf(urdf("fixed", R"(<sphere radius="0.05"/>)"));
  ASSERT_EQ(parts.size(), 2U);
  EXPECT_EQ(parts[1].shape, MockupPart::Shape::kSphere);
  EXPECT_TRUE(parts[1].scale.isApprox(Eigen::Vector3d::Constant(0.1)));
}

TEST(TargetMockup, RefusesWhatIsNotOneRigidBodyOfPrimitives) {
  EXPECT_THROW(mockupFromUrdf("not xml"), std::invalid_argument);
  EXPECT_THROW(mockupFromUrdf(urdf("revolute", R"(<box size="0.1 0.1 0.1"/>)")), std::invalid_argument);
  EXPECT_THROW(mockupFromUrdf(urdf("fixed", R"(<mesh filename="package://x/y.stl"/>)")), std::invalid_argument);
}
