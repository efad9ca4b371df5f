// The docking port held in the odom frame (ROS-free): a Kalman filter over the estimates, and a
// prediction to any later time. This is what lets the final approach finish on odometry when the
// cameras are too close to see the target, and what the rotating target's feed-forward comes from.
//
// Model (the simulator's and the paper's test bed: a target robot that stands, turns in place, or
// drifts while turning): the target is a rigid body turning at a nearly constant rate w about a point
// c of the odom plane that moves at a nearly constant velocity u; the port sits at a fixed offset d
// from c in the target's frame:
//     port yaw       psi(t) = psi0 + w t              (filter 1: [psi, w], w a slow random walk)
//     port position  p(t) = c(t) + R(psi(t)) d,  c' = u  (filter 2: [c, d, u], linear given psi)
// so the port's velocity is u + w x R(psi) d; a still target is w = 0, u = 0. Pose noise is averaged
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
  bool yaw_rate_valid{false};        ///< `yaw_rate` is meaningful
  double yaw_rate{0.0};              ///< the port's angular velocity about odom z, rad/s
  std::uint8_t source{0};            ///< TargetEstimate.SOURCE_* of the estimate used
  std::string status;                ///< the estimator's reason when not valid
};

struct TrackConfig {
  double default_position_sigma_m{0.01};      ///< when the estimate gives none
  double default_yaw_sigma_rad{0.03};         ///< when the estimate gives none
  /// Floor of a yaw measurement's std. dev., per square metre of camera range (rad/m^2): a monocular
  /// orientation degrades with range much faster than its reprojection covariance says (in the
  /// simulator 0.1 deg at 0.5 m, 1.2 deg head-on at 1.4 m, 6 deg head-on at 2 m). Poses at 2-3 m,
  /// 10-28 deg off in some campaign runs, otherwise set a turn rate the blind finish followed.
  double yaw_sigma_per_range2{0.005};
  double yaw_rate_sigma_radps{0.02};          ///< std. dev. of a yaw rate taken from the estimate's twist
  /// Fuse the twist's yaw rate when valid. Off by default: the monocular twist is relative to the
  /// camera, and adding the chaser's odometry yaw rate to it left a bias (0.06 deg/s on a still
  /// target in the simulator) that the blind finish integrated into the docked yaw.
  bool use_estimate_yaw_rate{false};
  /// rad/s per sqrt(s): how fast the target's rate may change. Small, because a free target turns at
  /// a constant rate, and because this sets how long the filter averages the rate: with 0.005 the rate
  /// came out 0.08 deg/s (1 sigma) off after 12 s of 0.06 deg poses, 0.5 deg over a 7 s blind finish;
  /// with 0.0003 it is 0.01 deg/s.
  double yaw_rate_random_walk{0.0003};
  double centre_random_walk{0.002};          ///< m per sqrt(s): the turning centre's jitter (a turning target's centre stays put; 0.01 let it absorb the port's circle)
  /// Estimate a drift velocity u of the target (else u = 0). Off by default: over the few seconds a
  /// near-range camera sees the port, a drift and a turn are hard to tell apart, and modelling the
  /// drift costs a target that only turns ~1 cm of dead-reckoned accuracy (and gains the same for
  /// a drifting one); see README.md.
  bool model_target_drift{false};
  double centre_velocity_random_walk{0.005};  ///< m/s per sqrt(s): how fast the target's drift may change
  double initial_centre_speed_sigma_mps{0.05};  ///< prior on the target's drift speed
  double offset_random_walk{0.001};           ///< m per sqrt(s): the port offset (constant in truth)
  /// Prior on the port's offset from the turning centre, along the port axis (the test bed's target
  /// robots turn about their centre, the port 0.15 m ahead of it), and its std. dev.
  double initial_offset_m{0.15};
  double initial_offset_sigma_m{0.05};
  double initial_yaw_rate_sigma_radps{0.1};   ///< prior on the target's yaw rate
  double max_port_yaw_rate_radps{0.3};        ///< the estimated yaw rate is clamped to this
  double max_port_speed_mps{0.1};             ///< the predicted port speed is clamped to this
  double outlier_gate_sigma{6.0};             ///< innovations beyond this many sigmas are rejected (0: off)
  int outlier_reset_count{5};                 ///< this many rejections in a row: the target moved, restart
};

/// Throws std::invalid_argument naming the bad field.
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
  void propagate(double dt);
  void restartPosition(const Vec2& measured, double variance);
  Eigen::Matrix<double, 2, 6> positionJacobian() const;

  TrackConfig config_;
  // Filter 1: port yaw and yaw rate.
  Eigen::Vector2d yaw_state_{Eigen::Vector2d::Zero()};
  Eigen::Matrix2d yaw_cov_{Eigen::Matrix2d::Identity()};
  // Filter 2: turning centre c (0, 1), port offset d in the target frame (2, 3), drift u of c (4, 5).
  using Vector6d = Eigen::Matrix<double, 6, 1>;
  using Matrix6d = Eigen::Matrix<double, 6, 6>;
  Vector6d pos_state_{Vector6d::Zero()};
  Matrix6d pos_cov_{Matrix6d::Identity()};
  std::optional<double> last_position_stamp_s_;
  std::optional<double> last_orientation_stamp_s_;
  std::uint8_t last_source_{0};
  int position_outliers_{0};
  int yaw_outliers_{0};
};

}  // namespace docking_planner
