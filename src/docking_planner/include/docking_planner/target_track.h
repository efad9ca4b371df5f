// The docking port held in the odom frame from the estimates (ROS-free): the last good pose, its
// velocity and angular velocity (from the estimate's twist, or from successive poses, low-pass
// filtered), and a prediction to any later time. This is what lets the final approach finish on
// odometry when the cameras are too close to see the target.
#pragma once

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
  bool yaw_rate_valid{false};        ///< `yaw_rate` is meaningful
  double yaw_rate{0.0};              ///< the port's angular velocity about odom z, rad/s
  std::uint8_t source{0};            ///< TargetEstimate.SOURCE_* of the estimate used
  std::string status;                ///< the estimator's reason when not valid
};

struct TrackConfig {
  double velocity_filter_time_s{0.8};  ///< low-pass time constant of the port's velocity estimates
  double min_difference_dt_s{0.02};    ///< poses closer in time than this are not differenced
  double max_port_speed_mps{0.1};      ///< the estimated port velocity is clamped to this (noise guard)
  double max_port_yaw_rate_radps{0.3}; ///< the estimated port yaw rate is clamped to this
  bool use_estimate_yaw_rate{true};    ///< prefer the estimate's twist to differenced yaw, when valid
};

void validate(const TrackConfig& config);

struct TrackUpdate {
  bool accepted{false};
  std::string reason;  ///< why not
};

class TargetTrack {
 public:
  explicit TargetTrack(const TrackConfig& config);

  /// Takes a valid observation. Rejects non-finite values and stamps not after the last one taken.
  TrackUpdate update(const TargetObservation& observation);

  bool hasPosition() const { return last_position_stamp_s_.has_value(); }
  bool hasOrientation() const { return last_orientation_stamp_s_.has_value(); }
  /// Stamp of the last observation taken, or -inf.
  double lastStamp() const;
  double lastOrientationStamp() const;
  std::uint8_t lastSource() const { return last_source_; }

  /// The port at time `now_s`, predicted from the last observation with the filtered velocities.
  /// Requires hasPosition(). Without an orientation yet, yaw is 0 and meaningless.
  PortState predict(double now_s) const;

  void reset();

 private:
  TrackConfig config_;
  Pose2D pose_;
  Vec2 velocity_{Vec2::Zero()};
  double yaw_rate_{0.0};
  std::optional<double> last_position_stamp_s_;
  std::optional<double> last_orientation_stamp_s_;
  std::uint8_t last_source_{0};
};

}  // namespace docking_planner
