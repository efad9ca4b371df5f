// rostest: mono_pose estimates from the simulated cameras against the simulator's truth at the same
// image stamp (mono_sim_near_1m.test, mono_sim_dark_1m.test).
//
// Parameters (private):
//   mode                       "visible" (perception/mono_visible/estimate) or "ir" (perception/mono_ir/estimate)
//   min_frames                 estimates paired with a truth message before judging
//   min_detection_rate         fraction of those that must be valid
//   max_median_position_error_m, max_median_orientation_error_deg   over the valid ones (orientation: the
//                              ones that claim it; a withheld one must say why in `status`)
//   min_orientation_claimed_rate  share of the valid ones that must claim their orientation (0.8)
//   max_position_error_m       every valid estimate (catches a wrong pattern or a flipped pose)
//   check_other                also judge the other instance: each estimate invalid with a reason, or valid
//                              and within max_position_error_m of its own camera's truth (the dark scene: the
//                              visible image shows the face dimly, in noise; a pose there must be right)
//   wall_timeout_s             wall time to collect min_frames (sim time runs as fast as the machine can)
#include <algorithm>
#include <cmath>
#include <iostream>
#include <map>
#include <mutex>
#include <string>
#include <utility>
#include <vector>

#include <docking_msgs/TargetEstimate.h>
#include <docking_msgs/names.h>
#include <gtest/gtest.h>
#include <nav_msgs/Odometry.h>
#include <ros/ros.h>

namespace {

double median(std::vector<double> values) {
  std::sort(values.begin(), values.end());
  return values[values.size() / 2];
}

// Angle of the rotation between two unit quaternions, degrees.
double angleBetweenDeg(const geometry_msgs::Quaternion& a, const geometry_msgs::Quaternion& b) {
  const double dot = std::abs(a.x * b.x + a.y * b.y + a.z * b.z + a.w * b.w);
  return 2.0 * std::acos(std::min(1.0, dot)) * 180.0 / M_PI;
}

TEST(MonoPoseSimulation, EstimatesMatchTheTruth) {
  ros::NodeHandle nh;
  ros::NodeHandle private_nh("~");
  const std::string mode = private_nh.param<std::string>("mode", "visible");
  ASSERT_TRUE(mode == "visible" || mode == "ir") << "mode must be visible or ir, got " << mode;
  const bool visible = mode == "visible";
  const int min_frames = private_nh.param("min_frames", 30);
  const double min_detection_rate = private_nh.param("min_detection_rate", 0.9);
  const double max_median_position_error = private_nh.param("max_median_position_error_m", 0.01);
  const double max_median_orientation_error = private_nh.param("max_median_orientation_error_deg", 1.0);
  // A valid estimate may withhold its orientation (its covariance allows no claim, or IPPE is
  // undecided): at least this share of the valid ones must claim it.
  const double min_orientation_claimed_rate = private_nh.param("min_orientation_claimed_rate", 0.8);
  const double max_position_error = private_nh.param("max_position_error_m", 0.05);
  const bool check_other = private_nh.param("check_other", false);
  const double wall_timeout_s = private_nh.param("wall_timeout_s", 200.0);

  const std::string estimate_topic = visible ? docking_msgs::topics::kMonoVisibleEstimate
                                             : docking_msgs::topics::kMonoIrEstimate;
  const std::string other_topic = visible ? docking_msgs::topics::kMonoIrEstimate
                                          : docking_msgs::topics::kMonoVisibleEstimate;
  const std::string truth_topic = visible ? docking_msgs::topics::kTruthStereoLeft : docking_msgs::topics::kTruthIr;
  const std::string other_truth_topic = visible ? docking_msgs::topics::kTruthIr : docking_msgs::topics::kTruthStereoLeft;
  const std::string frame = visible ? docking_msgs::frames::kStereoLeftOptical : docking_msgs::frames::kIrOptical;

  std::mutex mutex;
  std::map<ros::Time, nav_msgs::Odometry> truth_by_stamp;
  std::map<ros::Time, docking_msgs::TargetEstimate> estimates_by_stamp;
  std::vector<docking_msgs::TargetEstimate> other_estimates;
  std::map<ros::Time, nav_msgs::Odometry> other_truth_by_stamp;
  ros::Subscriber truth_subscriber =
      nh.subscribe<nav_msgs::Odometry>(truth_topic, 200, [&](const nav_msgs::OdometryConstPtr& truth) {
        std::lock_guard<std::mutex> lock(mutex);
        truth_by_stamp[truth->header.stamp] = *truth;
      });
  ros::Subscriber estimate_subscriber = nh.subscribe<docking_msgs::TargetEstimate>(
      estimate_topic, 100, [&](const docking_msgs::TargetEstimateConstPtr& estimate) {
        std::lock_guard<std::mutex> lock(mutex);
        estimates_by_stamp[estimate->header.stamp] = *estimate;
      });
  ros::Subscriber other_subscriber;
  ros::Subscriber other_truth_subscriber;
  if (check_other) {
    other_subscriber = nh.subscribe<docking_msgs::TargetEstimate>(
        other_topic, 100, [&](const docking_msgs::TargetEstimateConstPtr& estimate) {
          std::lock_guard<std::mutex> lock(mutex);
          other_estimates.push_back(*estimate);
        });
    other_truth_subscriber =
        nh.subscribe<nav_msgs::Odometry>(other_truth_topic, 200, [&](const nav_msgs::OdometryConstPtr& truth) {
          std::lock_guard<std::mutex> lock(mutex);
          other_truth_by_stamp[truth->header.stamp] = *truth;
        });
  }

  using Pair = std::pair<docking_msgs::TargetEstimate, nav_msgs::Odometry>;
  auto pairs = [&]() {
    std::lock_guard<std::mutex> lock(mutex);
    std::vector<Pair> matched;
    for (const auto& [stamp, estimate] : estimates_by_stamp) {
      const auto truth = truth_by_stamp.find(stamp);
      if (truth != truth_by_stamp.end()) matched.emplace_back(estimate, truth->second);
    }
    return matched;
  };
  auto enoughOther = [&]() {
    std::lock_guard<std::mutex> lock(mutex);
    return !check_other || static_cast<int>(other_estimates.size()) >= min_frames;
  };
  const ros::WallTime deadline = ros::WallTime::now() + ros::WallDuration(wall_timeout_s);
  while (ros::ok() && ros::WallTime::now() < deadline &&
         (static_cast<int>(pairs().size()) < min_frames || !enoughOther())) {
    ros::spinOnce();
    ros::WallDuration(0.05).sleep();
  }
  const std::vector<Pair> matched = pairs();
  ASSERT_GE(static_cast<int>(matched.size()), min_frames)
      << "only " << matched.size() << " " << mode << " estimates matched a truth stamp within " << wall_timeout_s
      << " s wall time (" << estimates_by_stamp.size() << " estimates, " << truth_by_stamp.size()
      << " truth messages)";

  int valid = 0;
  std::vector<double> position_errors;
  std::vector<double> orientation_errors;
  std::map<std::string, int> reasons;
  for (const auto& [estimate, truth] : matched) {
    EXPECT_EQ(estimate.header.frame_id, frame);
    EXPECT_EQ(estimate.source, visible ? docking_msgs::TargetEstimate::SOURCE_MONO_VISIBLE
                                       : docking_msgs::TargetEstimate::SOURCE_MONO_IR);
    if (!estimate.valid) {
      EXPECT_FALSE(estimate.status.empty()) << "an invalid estimate must say why";
      ++reasons[estimate.status];
      continue;
    }
    ++valid;
    EXPECT_TRUE(estimate.position_valid);
    const auto& p = estimate.pose.pose.position;
    const auto& t = truth.pose.pose.position;
    const double error = std::sqrt((p.x - t.x) * (p.x - t.x) + (p.y - t.y) * (p.y - t.y) + (p.z - t.z) * (p.z - t.z));
    EXPECT_LT(error, max_position_error) << "estimate (" << p.x << ", " << p.y << ", " << p.z << ") truth (" << t.x
                                         << ", " << t.y << ", " << t.z << ") at " << estimate.header.stamp;
    position_errors.push_back(error);
    if (!estimate.orientation_valid) {
      EXPECT_NE(estimate.status.find("orientation withheld"), std::string::npos) << "a withheld orientation must say why";
      ++reasons[estimate.status.substr(0, estimate.status.find(':'))];
      continue;
    }
    orientation_errors.push_back(angleBetweenDeg(estimate.pose.pose.orientation, truth.pose.pose.orientation));
  }
  const double rate = static_cast<double>(valid) / static_cast<double>(matched.size());
  std::cout << "mono_" << mode << " vs truth: " << valid << " of " << matched.size() << " frames valid";
  if (!position_errors.empty()) std::cout << ", position error median " << 1e3 * median(position_errors) << " mm";
  if (!orientation_errors.empty()) std::cout << ", orientation error median " << median(orientation_errors) << " deg";
  std::cout << ", " << orientation_errors.size() << " claim their orientation\n";
  for (const auto& [reason, count] : reasons) std::cout << "  invalid or withheld " << count << "x: " << reason << "\n";
  EXPECT_GE(rate, min_detection_rate) << valid << " of " << matched.size() << " frames";
  ASSERT_FALSE(position_errors.empty());
  EXPECT_LE(median(position_errors), max_median_position_error);
  const double claimed_rate = valid > 0 ? static_cast<double>(orientation_errors.size()) / valid : 0.0;
  EXPECT_GE(claimed_rate, min_orientation_claimed_rate) << orientation_errors.size() << " of " << valid
                                                        << " valid estimates claim their orientation";
  if (!orientation_errors.empty()) {
    EXPECT_LE(median(orientation_errors), max_median_orientation_error);
  }

  if (check_other) {
    std::lock_guard<std::mutex> lock(mutex);
    ASSERT_GE(static_cast<int>(other_estimates.size()), min_frames)
        << "the other instance (" << other_topic << ") published only " << other_estimates.size() << " estimates";
    int other_valid = 0;
    int other_judged = 0;
    for (const docking_msgs::TargetEstimate& estimate : other_estimates) {
      if (!estimate.valid) {
        EXPECT_FALSE(estimate.status.empty()) << "an invalid estimate must say why";
        continue;
      }
      ++other_valid;
      const auto truth = other_truth_by_stamp.find(estimate.header.stamp);
      if (truth == other_truth_by_stamp.end()) continue;
      ++other_judged;
      const auto& p = estimate.pose.pose.position;
      const auto& t = truth->second.pose.pose.position;
      EXPECT_LT(std::sqrt((p.x - t.x) * (p.x - t.x) + (p.y - t.y) * (p.y - t.y) + (p.z - t.z) * (p.z - t.z)),
                max_position_error)
          << other_topic << " at " << estimate.header.stamp;
    }
    std::cout << other_topic << ": " << other_valid << " of " << other_estimates.size() << " valid, " << other_judged
              << " of them against the truth"
              << (other_estimates.empty() ? "" : ", last status: " + other_estimates.back().status) << "\n";
    EXPECT_EQ(other_judged, other_valid) << "every valid estimate of " << other_topic << " has a truth to judge it by";
  }
}

}  // namespace

int main(int argc, char** argv) {
  ::testing::InitGoogleTest(&argc, argv);
  ros::init(argc, argv, "test_mono_sim");
  ros::NodeHandle nh;
  return RUN_ALL_TESTS();
}
