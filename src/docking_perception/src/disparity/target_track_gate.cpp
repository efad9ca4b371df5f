#include "docking_perception/disparity/target_track_gate.h"

#include <algorithm>
#include <cmath>
#include <sstream>
#include <stdexcept>

#include <Eigen/Eigenvalues>

#include "number_text.h"

#include <docking_settings/setting_info.h>

namespace docking_perception {
namespace disparity {
namespace {

// Velocity smoothing of the track (fraction of the newest frame-to-frame velocity taken each frame):
// disparity depth noise at 6 m is ~0.16 m per frame, so a single difference is mostly noise.
constexpr double kVelocityGain = 0.2;
// Constants of the gate: its smallest radius, about the
// mockup's own size (a blob's centre moves that much with the target's yaw); the detection's position noise
// it adds, in sigmas (3: 99.7 % of a Gaussian's errors in one axis); how long the track lives without a
// confirmed detection (2 s: 15 frames at 7.5 Hz; the target moves at most 1 m meanwhile).
constexpr double kMinGateM = 0.3;
constexpr double kGateSigmas = 3.0;
constexpr double kTrackTimeoutS = 2.0;

std::string format(double value) { return disparity::formatNumber(value, 3); }

}  // namespace

TargetTrackGate::TargetTrackGate(const TrackGateParams& params) { setParams(params); }

void TargetTrackGate::setParams(const TrackGateParams& params) {
  docking_settings::validateSettings(params);
  params_ = params;
}

void TargetTrackGate::reset() {
  has_track_ = false;
  pending_frames_ = 0;
  velocity_mps_.setZero();
}

Eigen::Vector3d TargetTrackGate::predict(double stamp_s) const {
  return position_m_ + velocity_mps_ * std::max(0.0, stamp_s - last_stamp_s_);
}

double TargetTrackGate::gateRadius(double dt_s, const Eigen::Matrix3d& covariance_m2) const {
  const Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> solver(covariance_m2);
  const double largest_sigma = std::sqrt(std::max(0.0, solver.eigenvalues().maxCoeff()));
  return kMinGateM + params_.max_speed_mps * std::max(0.0, dt_s) + kGateSigmas * largest_sigma;
}

SearchHint TargetTrackGate::hint(double stamp_s) const {
  SearchHint hint;
  if (!params_.gate_enabled || !has_track_ || stamp_s - last_stamp_s_ > kTrackTimeoutS) return hint;
  hint.valid = true;
  hint.position_m = predict(stamp_s);
  // Without a detection's covariance yet: the gate of a still, noise-free detection; the detector
  // only uses it to prefer one target-shaped blob over another.
  hint.radius_m = gateRadius(stamp_s - last_stamp_s_, Eigen::Matrix3d::Zero()) +
                  kMinGateM;
  return hint;
}

void TargetTrackGate::startTrack(double stamp_s, const Eigen::Vector3d& position_m) {
  has_track_ = true;
  last_stamp_s_ = stamp_s;
  position_m_ = position_m;
  velocity_mps_.setZero();
  pending_frames_ = 0;
}

Detection TargetTrackGate::apply(double stamp_s, const Detection& detection) {
  if (stamp_s < last_seen_stamp_s_) reset();
  last_seen_stamp_s_ = stamp_s;
  if (!params_.gate_enabled) return detection;
  if (has_track_ && stamp_s - last_stamp_s_ > kTrackTimeoutS) reset();
  if (!detection.found) return detection;

  const Eigen::Vector3d& measured = detection.position_m;
  if (!has_track_) {
    startTrack(stamp_s, measured);
    return detection;
  }
  const double dt = stamp_s - last_stamp_s_;
  const double gate = gateRadius(dt, detection.covariance_m2);
  const double distance = (measured - predict(stamp_s)).norm();
  if (distance <= gate) {
    if (dt > 0.0) {
      Eigen::Vector3d velocity =
          (1.0 - kVelocityGain) * velocity_mps_ + kVelocityGain * (measured - position_m_) / dt;
      // The gate assumes at most max_speed_mps: a faster track velocity is noise.
      if (velocity.norm() > params_.max_speed_mps) {
        velocity *= params_.max_speed_mps / velocity.norm();
      }
      velocity_mps_ = velocity;
    }
    position_m_ = measured;
    last_stamp_s_ = stamp_s;
    pending_frames_ = 0;
    return detection;
  }

  // A jump: count it towards a new track if it agrees with the previous jump.
  const bool continues_pending =
      pending_frames_ > 0 &&
      (measured - pending_position_m_).norm() <=
          gateRadius(stamp_s - pending_stamp_s_, detection.covariance_m2);
  pending_frames_ = continues_pending ? pending_frames_ + 1 : 1;
  pending_position_m_ = measured;
  pending_stamp_s_ = stamp_s;
  if (pending_frames_ >= params_.confirm_frames) {
    startTrack(stamp_s, measured);
    return detection;
  }
  Detection rejected = detection;
  rejected.found = false;
  rejected.outcome = TrackOutcome::kOffTrack;
  rejected.reason = "off track: blob " + format(distance) + " m from the tracked target (gate " +
                    format(gate) + " m); " + std::to_string(pending_frames_) + " of " +
                    std::to_string(params_.confirm_frames) + " frames to confirm a new position";
  return rejected;
}

}  // namespace disparity
}  // namespace docking_perception
