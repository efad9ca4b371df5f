#include <gtest/gtest.h>

#include <cmath>

#include "docking_perception/arbiter/frame_change.h"

using docking_perception::arbiter::changeFrame;
using docking_perception::arbiter::changeFrameRigidMount;
using docking_perception::arbiter::Matrix6d;
using docking_perception::arbiter::PoseWithCovariance3;
using docking_perception::arbiter::TwistWithCovariance3;

namespace {

// The IR camera seen from the left stereo camera: both look along base x; IR sits 0.05 m to the
// right (optical +x) and 0.05 m higher (optical -y). A small roll makes the rotation non-trivial.
Eigen::Isometry3d leftFromIr() {
  Eigen::Isometry3d t = Eigen::Isometry3d::Identity();
  t.translate(Eigen::Vector3d(0.05, -0.05, 0.0));
  t.rotate(Eigen::AngleAxisd(0.3, Eigen::Vector3d::UnitZ()));
  return t;
}

}  // namespace

TEST(FrameChange, PoseFollowsTheTransform) {
  PoseWithCovariance3 in;
  in.position = Eigen::Vector3d(0.1, 0.0, 1.0);
  in.orientation = Eigen::Quaterniond(Eigen::AngleAxisd(0.5, Eigen::Vector3d::UnitY()));
  const Eigen::Isometry3d t = leftFromIr();
  const PoseWithCovariance3 out = changeFrame(t, in);
  EXPECT_TRUE(out.position.isApprox(t * in.position, 1e-12));
  // Composing the target pose: out_T_target = out_T_in * in_T_target.
  Eigen::Isometry3d in_target = Eigen::Isometry3d::Identity();
  in_target.translate(in.position);
  in_target.rotate(in.orientation);
  const Eigen::Isometry3d expected = t * in_target;
  EXPECT_TRUE(out.orientation.toRotationMatrix().isApprox(expected.rotation(), 1e-12));
}

TEST(FrameChange, CovarianceIsRotatedNotTranslated) {
  PoseWithCovariance3 in;
  in.position = Eigen::Vector3d(0.0, 0.0, 2.0);
  // Depth (optical z) is the uncertain axis.
  in.covariance = Matrix6d::Identity() * 1e-4;
  in.covariance(2, 2) = 0.09;
  Eigen::Isometry3d quarter_turn = Eigen::Isometry3d::Identity();
  quarter_turn.translate(Eigen::Vector3d(5.0, 5.0, 5.0));
  quarter_turn.rotate(Eigen::AngleAxisd(M_PI / 2, Eigen::Vector3d::UnitX()));  // z -> -y
  const PoseWithCovariance3 out = changeFrame(quarter_turn, in);
  EXPECT_NEAR(out.covariance(1, 1), 0.09, 1e-12);  // the uncertainty is now along y
  EXPECT_NEAR(out.covariance(2, 2), 1e-4, 1e-12);
  EXPECT_NEAR(out.covariance(0, 0), 1e-4, 1e-12);
  EXPECT_TRUE(out.covariance.isApprox(out.covariance.transpose(), 1e-12));
  EXPECT_NEAR(out.covariance.trace(), in.covariance.trace(), 1e-12);
}

TEST(FrameChange, RigidMountTwistIsRotated) {
  TwistWithCovariance3 in;
  in.linear = Eigen::Vector3d(0.0, 0.0, -0.1);  // closing in along the optical axis
  in.angular = Eigen::Vector3d(0.0, -0.05, 0.0);  // turning about optical -y = base z
  in.covariance = Matrix6d::Identity() * 1e-3;
  in.covariance(0, 1) = in.covariance(1, 0) = 5e-4;
  const Eigen::Matrix3d r = leftFromIr().rotation();
  const TwistWithCovariance3 out = changeFrameRigidMount(r, in);
  EXPECT_TRUE(out.linear.isApprox(r * in.linear, 1e-12));
  EXPECT_TRUE(out.angular.isApprox(r * in.angular, 1e-12));
  EXPECT_NEAR(out.linear.norm(), 0.1, 1e-12);
  // Rotating back recovers the input covariance.
  const TwistWithCovariance3 back = changeFrameRigidMount(r.transpose(), out);
  EXPECT_TRUE(back.covariance.isApprox(in.covariance, 1e-12));
  EXPECT_FALSE(out.covariance.isApprox(in.covariance, 1e-6));  // the off-diagonal term moved
}
