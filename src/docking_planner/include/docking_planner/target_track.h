// The docking port held in the odom frame (ROS-free): a Kalman filter over the estimates, and a
// prediction to any later time. This is what lets the final approach finish on odometry when the
// cameras are too close to see the target, and what the rotating target's feed-forward comes from.
//
// Model (the simulator's and the paper's test bed: a target robot that stands or turns in place): the
// target is a rigid body turning at a nearly constant rate w about a point c of the odom plane that stays
// put (a random walk); the port sits at a fixed offset d from c in the target's frame:
//     port yaw       psi(t) = psi0 + w t              (filter 1: [psi, w], w a slow random walk)
//     port position  p(t) = c + R(psi(t)) d           (filter 2: [c, d], linear given psi)
// so the port's velocity is w x R(psi) d; a still target is w = 0. A drifting target is followed through
// the estimates, not modelled (README "The port held in odom"). Pose noise is averaged
// over seconds instead of being differenced (differencing amplifies it by sqrt(2)/dt, paper-notes.md
// "Velocities"), which keeps a dead-reckoned finish accurate.
#pragma once

#include <Eigen/Core>
#include <cstdint>
#include <optional>
#include <string>

#include "docking_planner/planar.h"
#include "docking_planner/safe_circle_approach.h"

namespace docking_planner {

/// One estimate of the port, already transformed into odom by the caller.
struct TargetObservation {
  double stamp_s{0.0};               ///< the image's stamp
  bool valid{false};                 ///< false: the estimator sees nothing (`status` says why)
  bool orientation_valid{false};     ///< `pose.yaw` is meaningful (false for a position-only source)
  Pose2D pose;                       ///< the port in odom: centre and port-axis direction
  double position_sigma_m{0.0};      ///< std. dev. of x and y; 0: use the configured default
  double yaw_sigma_rad{0.0};         ///< std. dev. of yaw; 0: use the configured default
  double range_m{0.0};               ///< camera to port (m), for the range-dependent yaw floor; 0: unknown
  std::uint8_t source{0};            ///< TargetEstimate.SOURCE_* of the estimate used
  std::string status;                ///< the estimator's reason when not valid
};

// Constants of the filter's method.
/// This many rejections in a row: the target did move, the filter restarts from them.
constexpr int kOutlierResetCount = 5;
/// Prior on the target's turn rate, rad/s (3 deg/s = 0.052).
constexpr double kInitialYawRateSigmaRadps = 0.1;
/// m per sqrt(s): how fast the port's offset from the turning centre may change (constant in truth).
constexpr double kOffsetRandomWalk = 0.001;
/// Measurement noise of an estimate that gives no position / orientation covariance.
constexpr double kDefaultPositionSigmaM = 0.01;
constexpr double kDefaultYawSigmaRad = 0.03;

/// The settings (settings/planner.yaml, TrackConfig): throws naming the bad field.
void validate(const TrackConfig& config);

struct TrackUpdate {
  bool accepted{false};
  std::string reason;  ///< why not, for people
  bool not_finite{false};  ///< refused because a value is NaN or infinite (the planner stops on it)
};

class TargetTrack {
 public:
  /// Throws std::invalid_argument for an invalid configuration.
  explicit TargetTrack(const TrackConfig& config);

  /// Takes a valid observation. Rejects non-finite values, stamps not after the last one taken, and
  /// outliers (until they persist: then the filter restarts from them).
  TrackUpdate update(const TargetObservation& observation);

  bool hasPosition() const { return last_position_stamp_s_.has_value(); }
  bool hasOrientation() const { return last_orientation_stamp_s_.has_value(); }
  /// Stamp of the last observation taken, or -inf.
  double lastStamp() const;
  double lastOrientationStamp() const;
  std::uint8_t lastSource() const { return last_source_; }

  /// The port at time `now_s`. Requires hasPosition(). Without an orientation yet, yaw is meaningless.
  PortState predict(double now_s) const;

  void reset();

 private:
  struct MeasurementNoise {
    double position_var{0.0};  ///< m^2, per axis
    double yaw_var{0.0};       ///< rad^2
  };
  // The stages of update(), in order.
  TrackUpdate checkObservation(const TargetObservation& observation) const;
  MeasurementNoise measurementNoise(const TargetObservation& observation) const;
  void start(const TargetObservation& observation, const MeasurementNoise& noise);
  std::string updateYaw(const TargetObservation& observation, double yaw_var);
  std::string updatePosition(const Vec2& measured, double position_var);
  void propagate(double dt);
  void restartPosition(const Vec2& measured, double variance);
  Eigen::Matrix<double, 2, 4> positionJacobian() const;

  TrackConfig config_;
  // Filter 1: port yaw and yaw rate.
  Eigen::Vector2d yaw_state_{Eigen::Vector2d::Zero()};
  Eigen::Matrix2d yaw_cov_{Eigen::Matrix2d::Identity()};
  // Filter 2: turning centre c (0, 1), port offset d in the target frame (2, 3).
  using Vector4d = Eigen::Matrix<double, 4, 1>;
  using Matrix4d = Eigen::Matrix<double, 4, 4>;
  Vector4d pos_state_{Vector4d::Zero()};
  Matrix4d pos_cov_{Matrix4d::Identity()};
  std::optional<double> last_position_stamp_s_;
  std::optional<double> last_orientation_stamp_s_;
  std::uint8_t last_source_{0};
  int position_outliers_{0};
  int yaw_outliers_{0};
};

}  // namespace docking_planner
