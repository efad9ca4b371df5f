// rostest (arbiter_node.test): the arbiter node's consistency check across two cameras.
#include <gtest/gtest.h>

#include <cmath>
#include <mutex>
#include <string>
#include <vector>

#include <docking_msgs/TargetEstimate.h>
#include <docking_msgs/names.h>
#include <ros/ros.h>
#include <std_msgs/String.h>
#include <tf2_eigen/tf2_eigen.h>
#include <tf2_ros/buffer.h>
#include <tf2_ros/transform_listener.h>

namespace {

constexpr double kDeg = M_PI / 180.0;
using docking_msgs::TargetEstimate;

class ArbiterNodeTest : public ::testing::Test {
 protected:
  void SetUp() override {
    visible_pub_ = nh_.advertise<TargetEstimate>(docking_msgs::topics::kMonoVisibleEstimate, 10);
    ir_pub_ = nh_.advertise<TargetEstimate>(docking_msgs::topics::kMonoIrEstimate, 10);
    fused_sub_ = nh_.subscribe(docking_msgs::topics::kTargetEstimate, 100, &ArbiterNodeTest::onFused, this);
    // The mount as the node sees it (from the launch file's static transform).
    tf2_ros::Buffer buffer;
    tf2_ros::TransformListener listener(buffer);
    const ros::WallTime deadline = ros::WallTime::now() + ros::WallDuration(30.0);
    while (ros::WallTime::now() < deadline) {
      if (buffer.canTransform(docking_msgs::frames::kIrOptical, docking_msgs::frames::kStereoLeftOptical,
                              ros::Time(0))) {
        ir_from_left_ = tf2::transformToEigen(buffer.lookupTransform(
            docking_msgs::frames::kIrOptical, docking_msgs::frames::kStereoLeftOptical, ros::Time(0)));
        have_mount_ = true;
        break;
      }
      ros::WallDuration(0.05).sleep();
    }
    const ros::WallTime connected = ros::WallTime::now() + ros::WallDuration(30.0);
    while (ros::WallTime::now() < connected &&
           (visible_pub_.getNumSubscribers() == 0 || ir_pub_.getNumSubscribers() == 0 ||
            fused_sub_.getNumPublishers() == 0)) {
      ros::WallDuration(0.05).sleep();
    }
  }

  void onFused(const docking_msgs::TargetEstimateConstPtr& msg) {
    std::lock_guard<std::mutex> lock(mutex_);
    fused_.push_back(*msg);
  }

  // The target 1 m ahead of the visible camera, turned `yaw_deg` about the camera's y axis, with the
  // pose's sigmas; expressed in `frame` (the IR one through the mount).
  TargetEstimate estimate(std::uint8_t source, ros::Time stamp, double yaw_deg, double sigma_m, double sigma_deg) {
    Eigen::Isometry3d target_in_left = Eigen::Translation3d(0.02, -0.01, 1.0) *
                                       Eigen::AngleAxisd(M_PI + yaw_deg * kDeg, Eigen::Vector3d::UnitY());
    TargetEstimate e;
    e.header.stamp = stamp;
    e.header.frame_id = docking_msgs::frames::kStereoLeftOptical;
    if (source == TargetEstimate::SOURCE_MONO_IR) {
      target_in_left = ir_from_left_ * target_in_left;
      e.header.frame_id = docking_msgs::frames::kIrOptical;
    }
    e.source = e.selected_source = source;
    e.valid = e.position_valid = e.orientation_valid = true;
    e.pose.pose = tf2::toMsg(target_in_left);
    for (int i = 0; i < 3; ++i) {
      e.pose.covariance[static_cast<std::size_t>(i * 7)] = sigma_m * sigma_m;
      e.pose.covariance[static_cast<std::size_t>((i + 3) * 7)] = std::pow(sigma_deg * kDeg, 2);
    }
    e.range_m = target_in_left.translation().norm();
    e.feature_inliers = 40;
    e.reprojection_error_px = 0.5;
    e.solver = "test";
    return e;
  }

  // Publishes IR then visible at one stamp and waits a little for the arbiter's answer.
  void publishPair(ros::Time stamp, double visible_yaw_deg) {
    ir_pub_.publish(estimate(TargetEstimate::SOURCE_MONO_IR, stamp, 0.0, 0.004, 1.0));
    ros::WallDuration(0.005).sleep();
    visible_pub_.publish(estimate(TargetEstimate::SOURCE_MONO_VISIBLE, stamp, visible_yaw_deg, 0.003, 0.5));
    ros::WallDuration(0.03).sleep();
  }

  // Waits (wall time, generous for a busy machine) until a fused estimate matching fusedAt() arrives.
  std::vector<TargetEstimate> waitFor(ros::Time stamp, bool valid) {
    const ros::WallTime deadline = ros::WallTime::now() + ros::WallDuration(10.0);
    std::vector<TargetEstimate> found = fusedAt(stamp, valid);
    while (found.empty() && ros::WallTime::now() < deadline) {
      ros::WallDuration(0.01).sleep();
      found = fusedAt(stamp, valid);
    }
    ros::WallDuration(0.05).sleep();  // anything else the arbiter publishes for it
    return fusedAt(stamp, valid);
  }

  std::vector<TargetEstimate> fusedAt(ros::Time stamp, bool valid) {
    std::lock_guard<std::mutex> lock(mutex_);
    std::vector<TargetEstimate> found;
    for (const auto& f : fused_) {
      if (f.valid == valid && (!valid || f.header.stamp == stamp)) found.push_back(f);
    }
    return found;
  }

  ros::NodeHandle nh_;
  ros::Publisher visible_pub_, ir_pub_;
  ros::Subscriber fused_sub_;
  Eigen::Isometry3d ir_from_left_{Eigen::Isometry3d::Identity()};
  bool have_mount_{false};
  std::mutex mutex_;
  std::vector<TargetEstimate> fused_;
};

TEST_F(ArbiterNodeTest, ChecksTheSourcesAgainstEachOtherInTheOutputFrame) {
  ASSERT_TRUE(have_mount_) << "no ir_optical_frame transform";
  ASSERT_GT(fused_sub_.getNumPublishers(), 0u) << "arbiter not up";

  // 1. Agreeing (once both are in the output frame): the visible pose is published, near.
  ros::Time stamp;
  for (int i = 0; i < 5; ++i) {
    stamp = ros::Time::now();
    publishPair(stamp, 0.0);
  }
  auto at = waitFor(stamp, true);
  ASSERT_FALSE(at.empty()) << "the agreeing pair was not published";
  EXPECT_EQ(at.back().selected_source, TargetEstimate::SOURCE_MONO_VISIBLE);

  // 2. Glare: the visible pose turns 15 deg with a 0.5 deg sigma; IR (and the previous output, well
  //    within timeout_s) stay.
  const ros::Time glare = ros::Time::now();
  publishPair(glare, 15.0);
  at = waitFor(glare, true);
  ASSERT_FALSE(at.empty()) << "nothing published for the glare frame";
  for (const auto& f : at) EXPECT_EQ(f.selected_source, TargetEstimate::SOURCE_MONO_IR);

  // 3. After the timeout (no previous output to ask), the same contradiction cannot be decided:
  //    invalid, with the code at the start of the status.
  ros::WallDuration(0.8).sleep();
  {
    std::lock_guard<std::mutex> lock(mutex_);
    fused_.clear();
  }
  const ros::Time undecided = ros::Time::now();
  publishPair(undecided, 15.0);
  const ros::WallTime deadline = ros::WallTime::now() + ros::WallDuration(10.0);
  bool coded = false;
  std::string statuses;
  while (!coded && ros::WallTime::now() < deadline) {
    ros::WallDuration(0.01).sleep();
    statuses.clear();
    for (const auto& f : fusedAt(undecided, false)) {
      coded = coded || f.status.rfind("sources_disagree:", 0) == 0;
      statuses += f.status + "\n";
    }
  }
  EXPECT_TRUE(coded) << "invalid estimates seen:\n" << statuses;
  ros::WallDuration(0.1).sleep();  // anything valid the arbiter might (wrongly) publish for it
  for (const auto& f : fusedAt(undecided, true)) {
    EXPECT_NE(f.selected_source, TargetEstimate::SOURCE_MONO_VISIBLE) << "the contradicted visible pose was published";
  }
}

}  // namespace

int main(int argc, char** argv) {
  ::testing::InitGoogleTest(&argc, argv);
  ros::init(argc, argv, "test_arbiter_node");
  ros::AsyncSpinner spinner(1);
  spinner.start();
  return RUN_ALL_TESTS();
}
