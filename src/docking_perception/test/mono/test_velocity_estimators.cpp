#include <gtest/gtest.h>

#include <cmath>
#include <opencv2/core.hpp>

#include "docking_perception/mono/velocity_estimators.h"
#include "synthetic_scene.h"

using namespace docking_perception::mono;  // NOLINT: test file

namespace {

// A target drifting at constant linear and angular velocity (camera frame).
struct Trajectory {
  Eigen::Vector3d p0{0.1, -0.05, 1.2};
  Eigen::Vector3d velocity{0.03, -0.01, -0.05};      // m/s
  Eigen::Vector3d angular_velocity{0.0, 0.1, 0.02};  // rad/s
  Eigen::Matrix3d r0 = synthetic::facingRotation(0.2);
  Eigen::Vector3d position(double t) const { return p0 + velocity * t; }
  Eigen::Matrix3d rotation(double t) const { return rotationExp(angular_velocity * t) * r0; }
};

constexpr double kPositionSigma = 0.005;               // m
constexpr double kAngleSigma = 0.5 * M_PI / 180.0;     // rad

PoseWithCovariance noisyPose(const Trajectory& trajectory, double t, cv::RNG* rng) {
  PoseWithCovariance pose;
  pose.translation = trajectory.position(t) +
                     Eigen::Vector3d(rng->gaussian(kPositionSigma), rng->gaussian(kPositionSigma), rng->gaussian(kPositionSigma));
  pose.rotation = rotationExp(Eigen::Vector3d(rng->gaussian(kAngleSigma), rng->gaussian(kAngleSigma),
                                              rng->gaussian(kAngleSigma))) *
                  trajectory.rotation(t);
  pose.covariance.setZero();
  pose.covariance.diagonal() << Eigen::Vector3d::Constant(kPositionSigma * kPositionSigma),
      Eigen::Vector3d::Constant(kAngleSigma * kAngleSigma);
  return pose;
}

}  // namespace

// The truth moves at exactly constant velocity, so a small process noise is the right model: with
// q = 1e-5, 5 mm / 0.5 deg pose noise at ~30 Hz, the filter's steady-state velocity sigma is ~2.5 mm/s
// and ~0.15 deg/s per axis (window ~0.5 s).
ConstantVelocityFilterParams smoothParams() {
  ConstantVelocityFilterParams params;
  params.accel_noise = 1e-5;
  params.angular_accel_noise = 1e-5;
  params.gate_chi2 = 0.0;  // the gate (99.9 %) would drop ~1 in 1000 good poses; tested on its own below
  return params;
}

TEST(ConstantVelocityFilter, ConvergesOnAConstantVelocityTrajectoryWithVariableDt) {
  const Trajectory trajectory;
  ConstantVelocityFilter filter(smoothParams());
  cv::RNG rng(42);
  double t = 0.0;
  std::string reason;
  double sum_linear_error2 = 0.0;
  double sum_angular_error2 = 0.0;
  double sum_position_error2 = 0.0;
  int late_samples = 0;
  while (t < 6.0) {
    ASSERT_TRUE(filter.update(t, noisyPose(trajectory, t, &rng), &reason)) << reason;
    if (t > 3.0) {
      const TwistWithCovariance twist = filter.twist();
      ASSERT_TRUE(twist.valid);
      sum_linear_error2 += (twist.linear - trajectory.velocity).squaredNorm();
      sum_angular_error2 += (twist.angular - trajectory.angular_velocity).squaredNorm();
      sum_position_error2 += (filter.pose().translation - trajectory.position(t)).squaredNorm();
      ++late_samples;
    }
    t += rng.uniform(0.025, 0.05);  // 20-40 Hz, irregular
  }
  // Goals of the issue: 1 cm/s and 1 deg/s (RMS after convergence). Raw frame differences at this
  // rate would be ~25 cm/s.
  EXPECT_LT(std::sqrt(sum_linear_error2 / late_samples), 0.01);
  EXPECT_LT(std::sqrt(sum_angular_error2 / late_samples), 1.0 * M_PI / 180.0);
  // The filtered position is better than a single measurement (3D rms of the noise: 8.7 mm).
  EXPECT_LT(std::sqrt(sum_position_error2 / late_samples), 0.5 * std::sqrt(3.0) * kPositionSigma);
  // The reported velocity uncertainty is honest: error within 4 sigma on each axis at the end.
  const TwistWithCovariance twist = filter.twist();
  for (int i = 0; i < 3; ++i) {
    EXPECT_LT(std::abs(twist.linear(i) - trajectory.velocity(i)), 4.0 * std::sqrt(twist.covariance(i, i)));
    EXPECT_LT(std::abs(twist.angular(i) - trajectory.angular_velocity(i)),
              4.0 * std::sqrt(twist.covariance(3 + i, 3 + i)));
  }
}

TEST(ConstantVelocityFilter, ShortGapIsBridgedAndLongGapRestarts) {
  const Trajectory trajectory;
  ConstantVelocityFilterParams params;
  params.max_gap_s = 0.5;
  params.accel_noise = 1e-5;
  params.angular_accel_noise = 1e-5;
  params.gate_chi2 = 0.0;
  ConstantVelocityFilter filter(params);
  cv::RNG rng(7);
  std::string reason;
  double t = 0.0;
  for (; t < 3.0; t += 0.033) ASSERT_TRUE(filter.update(t, noisyPose(trajectory, t, &rng), &reason));
  // 0.4 s without poses (target hidden), then it comes back: the filter predicted through the gap.
  t += 0.4;
  ASSERT_TRUE(filter.update(t, noisyPose(trajectory, t, &rng), &reason)) << reason;
  EXPECT_TRUE(filter.twist().valid);
  EXPECT_LT((filter.twist().linear - trajectory.velocity).norm(), 0.015);
  const int updates_before = filter.updatesSinceRestart();
  // 1 s gap: longer than max_gap_s, so the filter restarts and the velocity is unknown until the next pose.
  t += 1.0;
  reason.clear();
  ASSERT_TRUE(filter.update(t, noisyPose(trajectory, t, &rng), &reason));
  EXPECT_NE(reason.find("restarted"), std::string::npos) << reason;
  EXPECT_EQ(filter.updatesSinceRestart(), 1);
  EXPECT_GT(updates_before, 1);
  EXPECT_FALSE(filter.twist().valid);
  t += 0.033;
  ASSERT_TRUE(filter.update(t, noisyPose(trajectory, t, &rng), &reason));
  EXPECT_TRUE(filter.twist().valid);
}

TEST(ConstantVelocityFilter, RejectsOutOfOrderAndRepeatedStamps) {
  const Trajectory trajectory;
  ConstantVelocityFilter filter;
  cv::RNG rng(9);
  std::string reason;
  ASSERT_TRUE(filter.update(1.0, noisyPose(trajectory, 1.0, &rng), &reason));
  ASSERT_TRUE(filter.update(1.1, noisyPose(trajectory, 1.1, &rng), &reason));
  const Eigen::Vector3d before = filter.pose().translation;
  EXPECT_FALSE(filter.update(1.05, noisyPose(trajectory, 1.05, &rng), &reason));
  EXPECT_NE(reason.find("out of order"), std::string::npos) << reason;
  EXPECT_FALSE(filter.update(1.1, noisyPose(trajectory, 1.1, &rng), &reason));
  EXPECT_DOUBLE_EQ(filter.lastStamp(), 1.1);
  EXPECT_EQ((filter.pose().translation - before).norm(), 0.0);
}

TEST(ConstantVelocityFilter, GateRejectsAnOutlierThenRestartsOnPersistentJump) {
  const Trajectory trajectory;
  ConstantVelocityFilter filter{ConstantVelocityFilterParams()};
  cv::RNG rng(11);
  std::string reason;
  double t = 0.0;
  int rejected = 0;
  for (; t < 2.0; t += 0.033) rejected += filter.update(t, noisyPose(trajectory, t, &rng), &reason) ? 0 : 1;
  EXPECT_LE(rejected, 1);  // consistent poses pass a 99.9 % gate
  PoseWithCovariance jumped = noisyPose(trajectory, t, &rng);
  jumped.translation.z() += 0.5;  // a wrong solution half a metre off
  EXPECT_FALSE(filter.update(t, jumped, &reason));
  EXPECT_LT((filter.pose().translation - trajectory.position(t - 0.033)).norm(), 0.02);
  t += 0.033;
  jumped = noisyPose(trajectory, t, &rng);
  jumped.translation.z() += 0.5;
  EXPECT_FALSE(filter.update(t, jumped, &reason));
  t += 0.033;
  jumped = noisyPose(trajectory, t, &rng);
  jumped.translation.z() += 0.5;
  EXPECT_TRUE(filter.update(t, jumped, &reason));  // third in a row: the target really is there
  EXPECT_NEAR(filter.pose().translation.z(), jumped.translation.z(), 1e-9);
}

TEST(FrameDifferenceVelocity, ExactOnNoiselessPosesAndNoisyOtherwise) {
  const Trajectory trajectory;
  FrameDifferenceVelocity difference(0.5);
  std::string reason;
  PoseWithCovariance a;
  a.translation = trajectory.position(1.0);
  a.rotation = trajectory.rotation(1.0);
  PoseWithCovariance b;
  b.translation = trajectory.position(1.04);
  b.rotation = trajectory.rotation(1.04);
  ASSERT_TRUE(difference.update(1.0, a, &reason));
  EXPECT_FALSE(difference.twist().valid);
  ASSERT_TRUE(difference.update(1.04, b, &reason));
  ASSERT_TRUE(difference.twist().valid);
  EXPECT_LT((difference.twist().linear - trajectory.velocity).norm(), 1e-9);
  EXPECT_LT((difference.twist().angular - trajectory.angular_velocity).norm(), 1e-9);
  // Covariance of a difference: (C_a + C_b) / dt^2 (identity covariances here).
  EXPECT_NEAR(difference.twist().covariance(0, 0), 2.0 / (0.04 * 0.04), 1e-6);
  EXPECT_FALSE(difference.update(1.02, a, &reason));
  // A gap longer than max_gap: no velocity from that pair.
  ASSERT_TRUE(difference.update(2.0, a, &reason));
  EXPECT_FALSE(difference.twist().valid);
}

// The filter's purpose, measured: on the same noisy poses its velocity error is several times smaller
// than the paper's frame difference.
TEST(VelocityComparison, FilterBeatsFrameDifference) {
  const Trajectory trajectory;
  ConstantVelocityFilter filter(smoothParams());
  FrameDifferenceVelocity difference(0.5);
  cv::RNG rng(5);
  std::string reason;
  double filter_error2 = 0.0;
  double difference_error2 = 0.0;
  int samples = 0;
  for (double t = 0.0; t < 5.0; t += 0.033) {
    const PoseWithCovariance pose = noisyPose(trajectory, t, &rng);
    filter.update(t, pose, &reason);
    difference.update(t, pose, &reason);
    if (t > 2.0) {
      filter_error2 += (filter.twist().linear - trajectory.velocity).squaredNorm();
      difference_error2 += (difference.twist().linear - trajectory.velocity).squaredNorm();
      ++samples;
    }
  }
  EXPECT_LT(std::sqrt(filter_error2 / samples) * 5.0, std::sqrt(difference_error2 / samples));
}
