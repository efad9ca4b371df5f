// rostest: disparity estimates from the simulated cameras against the simulator's truth at the same
// image stamp (see disparity_sim_still_3m.test).
#include <algorithm>
#include <cmath>
#include <iostream>
#include <map>
#include <mutex>
#include <vector>

#include <docking_msgs/TargetEstimate.h>
#include <docking_msgs/names.h>
#include <gtest/gtest.h>
#include <nav_msgs/Odometry.h>
#include <ros/ros.h>
#include <stereo_msgs/DisparityImage.h>

namespace {

struct Pair {
  docking_msgs::TargetEstimate estimate;
  nav_msgs::Odometry truth;
};

TEST(DisparitySimulation, EstimatesAreWithinFivePercentOfTheTruth) {
  ros::NodeHandle nh;
  ros::NodeHandle private_nh("~");
  const int min_frames = private_nh.param("min_frames", 30);
  const double max_error_fraction = private_nh.param("max_position_error_fraction", 0.05);
  const double min_detection_rate = private_nh.param("min_detection_rate", 0.9);
  const double wall_timeout_s = private_nh.param("wall_timeout_s", 300.0);
  // The far stage's tracking window while tracking (config/far_stereo.yaml): at least this many of the matched
  // estimates come from a disparity image narrower than the calibrated width; 0: not checked.
  const int min_window_frames = private_nh.param("min_window_frames", 0);
  const int calibrated_width = private_nh.param("calibrated_width", 640);

  std::mutex mutex;
  std::map<ros::Time, nav_msgs::Odometry> truth_by_stamp;
  std::map<ros::Time, docking_msgs::TargetEstimate> estimates_by_stamp;
  std::map<ros::Time, int> disparity_width_by_stamp;
  ros::Subscriber disparity_subscriber = nh.subscribe<stereo_msgs::DisparityImage>(
      docking_msgs::topics::kStereoDisparity, 10, [&](const stereo_msgs::DisparityImageConstPtr& disparity) {
        std::lock_guard<std::mutex> lock(mutex);
        disparity_width_by_stamp[disparity->header.stamp] = static_cast<int>(disparity->image.width);
      });
  ros::Subscriber truth_subscriber = nh.subscribe<nav_msgs::Odometry>(
      docking_msgs::topics::kTruthStereoLeft, 100, [&](const nav_msgs::OdometryConstPtr& truth) {
        std::lock_guard<std::mutex> lock(mutex);
        truth_by_stamp[truth->header.stamp] = *truth;
      });
  ros::Subscriber estimate_subscriber = nh.subscribe<docking_msgs::TargetEstimate>(
      docking_msgs::topics::kDisparityEstimate, 100,
      [&](const docking_msgs::TargetEstimateConstPtr& estimate) {
        std::lock_guard<std::mutex> lock(mutex);
        estimates_by_stamp[estimate->header.stamp] = *estimate;
      });

  // Pairs of estimate and truth with the same image stamp.
  auto pairs = [&]() {
    std::lock_guard<std::mutex> lock(mutex);
    std::vector<Pair> matched;
    for (const auto& [stamp, estimate] : estimates_by_stamp) {
      const auto truth = truth_by_stamp.find(stamp);
      if (truth != truth_by_stamp.end()) matched.push_back({estimate, truth->second});
    }
    return matched;
  };
  // Matched estimates made on a tracking window.
  auto windowed = [&](const std::vector<Pair>& matched) {
    std::lock_guard<std::mutex> lock(mutex);
    int count = 0;
    for (const Pair& pair : matched) {
      const auto width = disparity_width_by_stamp.find(pair.estimate.header.stamp);
      if (width != disparity_width_by_stamp.end() && width->second < calibrated_width) ++count;
    }
    return count;
  };
  const ros::WallTime deadline = ros::WallTime::now() + ros::WallDuration(wall_timeout_s);
  while (ros::ok() && ros::WallTime::now() < deadline &&
         (static_cast<int>(pairs().size()) < min_frames || windowed(pairs()) < min_window_frames)) {
    ros::spinOnce();
    ros::WallDuration(0.05).sleep();
  }
  const std::vector<Pair> matched = pairs();
  ASSERT_GE(static_cast<int>(matched.size()), min_frames)
      << "only " << matched.size() << " estimates matched a truth stamp within " << wall_timeout_s
      << " s wall time (" << estimates_by_stamp.size() << " estimates, " << truth_by_stamp.size()
      << " truth messages)";

  const int window_frames = windowed(matched);
  EXPECT_GE(window_frames, min_window_frames)
      << "only " << window_frames << " of " << matched.size()
      << " estimates came from a tracking window: did far_stereo_rectify switch while "
         "tracking?";

  int valid = 0;
  std::vector<double> range_errors;
  for (const Pair& pair : matched) {
    EXPECT_EQ(pair.estimate.header.frame_id, docking_msgs::frames::kStereoLeftOptical);
    EXPECT_EQ(pair.truth.header.frame_id, docking_msgs::frames::kStereoLeftOptical);
    if (!pair.estimate.valid) {
      ADD_FAILURE() << "not found at " << pair.estimate.header.stamp << ": " << pair.estimate.status;
      continue;
    }
    ++valid;
    const auto& p = pair.estimate.pose.pose.position;
    const auto& t = pair.truth.pose.pose.position;
    const double range = std::sqrt(t.x * t.x + t.y * t.y + t.z * t.z);
    const double error = std::sqrt((p.x - t.x) * (p.x - t.x) + (p.y - t.y) * (p.y - t.y) +
                                   (p.z - t.z) * (p.z - t.z));
    EXPECT_LT(error, max_error_fraction * range)
        << "estimate (" << p.x << ", " << p.y << ", " << p.z << ") truth (" << t.x << ", " << t.y
        << ", " << t.z << ") at " << pair.estimate.header.stamp;
    EXPECT_NEAR(pair.estimate.range_m, range, max_error_fraction * range);
    range_errors.push_back(std::abs(pair.estimate.range_m - range) / range);
  }
  if (!range_errors.empty()) {
    std::sort(range_errors.begin(), range_errors.end());
    std::cout << "disparity vs truth: " << valid << " of " << matched.size() << " frames found ("
              << window_frames << " on a window), range error median " << 100.0 * range_errors[range_errors.size() / 2]
              << " %, max " << 100.0 * range_errors.back() << " %\n";
  }
  const double rate = static_cast<double>(valid) / static_cast<double>(matched.size());
  EXPECT_GE(rate, min_detection_rate) << valid << " of " << matched.size() << " frames";
}

}  // namespace

int main(int argc, char** argv) {
  ::testing::InitGoogleTest(&argc, argv);
  ros::init(argc, argv, "test_disparity_sim");
  ros::NodeHandle nh;
  return RUN_ALL_TESTS();
}
