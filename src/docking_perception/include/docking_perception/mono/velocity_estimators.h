// The target's linear and angular velocity (relative to the camera, camera frame) from successive poses.
//
// FrameDifferenceVelocity: the paper's method, (p_k - p_k-1) / dt and Log(R_k R_k-1^T) / dt, with the
// covariance of the difference of two independent poses. Noisy: sigma_v ~ sqrt(2) sigma_p / dt.
//
// ConstantVelocityFilter: an error-state Kalman filter with state (p, v, R, w): position and linear
// velocity, orientation (kept as a rotation matrix, its error as a 3-vector in the camera frame, the
// same convention as the pose covariance) and angular velocity. Motion model: constant velocity driven
// by white linear / angular acceleration (spectral densities accel_noise, angular_accel_noise), so the
// process noise scales correctly with any dt. Measurements: the full pose with its covariance.
// Out-of-order or repeated stamps are rejected (state untouched); a gap longer than max_gap_s restarts
// the filter from the new pose (a stale velocity must not be extrapolated over a long blackout);
// a measurement failing the chi-square gate is rejected, and after kMaxConsecutiveRejections in a row the
// filter restarts from the measurement (the target really moved, or the filter was wrong).
#pragma once

#include <Eigen/Core>
#include <string>

#include "docking_perception/mono/mono_pose_settings.h"
#include "docking_perception/mono/pose_types.h"

namespace docking_perception {
namespace mono {

// Gated poses in a row after which the filter restarts on them: at 99.9 % a consistent pose is gated about
// once in 1000, three in a row about never; at 15-30 Hz a real jump costs 0.1-0.2 s.
constexpr int kMaxConsecutiveRejections = 3;

class FrameDifferenceVelocity {
 public:
  explicit FrameDifferenceVelocity(double max_gap_s = 0.5) : max_gap_s_(max_gap_s) {}
  void setMaxGap(double max_gap_s) { max_gap_s_ = max_gap_s; }
  // False (with the reason) for an out-of-order stamp; the stored pose is then kept.
  bool update(double stamp_s, const PoseWithCovariance& pose, std::string* reason);
  // Valid after two poses no more than max_gap_s apart.
  const TwistWithCovariance& twist() const { return twist_; }
  void reset();

 private:
  double max_gap_s_;
  bool has_previous_ = false;
  double previous_stamp_s_ = 0.0;
  PoseWithCovariance previous_;
  TwistWithCovariance twist_;
};

// ConstantVelocityFilterParams is declared in settings/mono_pose.yaml (generated header). The spectral
// densities: smaller, smoother velocity and slower response; the window is ~ (sigma_pose^2 dt / q)^(1/4):
// with 2 mm poses at 30 Hz and q = 1e-3 about 0.1 s, giving ~1 cm/s velocity noise.

class ConstantVelocityFilter {
 public:
  explicit ConstantVelocityFilter(const ConstantVelocityFilterParams& params = ConstantVelocityFilterParams())
      : params_(params) {}
  void setParams(const ConstantVelocityFilterParams& params) { params_ = params; }

  // Fuses one pose. False (with the reason) when the stamp is not after the last one, or the gate
  // rejected the measurement. A restart (first pose, gap, repeated rejections) returns true.
  bool update(double stamp_s, const PoseWithCovariance& pose, std::string* reason);
  // The pose predicted at a stamp (for the tracking region). False before the first update.
  bool predict(double stamp_s, PoseWithCovariance* pose) const;

  bool initialized() const { return initialized_; }
  int updatesSinceRestart() const { return updates_since_restart_; }
  double lastStamp() const { return stamp_s_; }
  // Valid after two fused poses since the last restart.
  TwistWithCovariance twist() const;
  // The filtered pose at the last update.
  PoseWithCovariance pose() const;
  void reset();

 private:
  using Matrix12d = Eigen::Matrix<double, 12, 12>;
  void restart(double stamp_s, const PoseWithCovariance& pose);
  void propagate(double dt, Eigen::Vector3d* position, Eigen::Matrix3d* rotation, Matrix12d* covariance) const;

  ConstantVelocityFilterParams params_;
  bool initialized_ = false;
  int updates_since_restart_ = 0;
  int consecutive_rejections_ = 0;
  double stamp_s_ = 0.0;
  // State: position, linear velocity, orientation, angular velocity; error-state order (dp, dv, dtheta, dw).
  Eigen::Vector3d position_ = Eigen::Vector3d::Zero();
  Eigen::Vector3d velocity_ = Eigen::Vector3d::Zero();
  Eigen::Matrix3d rotation_ = Eigen::Matrix3d::Identity();
  Eigen::Vector3d angular_velocity_ = Eigen::Vector3d::Zero();
  Matrix12d covariance_ = Matrix12d::Identity();
};

}  // namespace mono
}  // namespace docking_perception
