#include "docking_planner/target_track.h"

#include <Eigen/Dense>
#include <algorithm>
#include <cmath>
#include <limits>
#include <stdexcept>
#include <string>

namespace docking_planner {
namespace {

Eigen::Matrix2d rotation(double a) {
  Eigen::Matrix2d r;
  r << std::cos(a), -std::sin(a), std::sin(a), std::cos(a);
  return r;
}

}  // namespace

void validate(const TrackConfig& c) { docking_settings::validateSettings(c); }

TargetTrack::TargetTrack(const TrackConfig& config) : config_(config) { validate(config_); }

void TargetTrack::reset() {
  yaw_state_.setZero();
  pos_state_.setZero();
  last_position_stamp_s_.reset();
  last_orientation_stamp_s_.reset();
  position_outliers_ = yaw_outliers_ = 0;
}

double TargetTrack::lastStamp() const {
  return last_position_stamp_s_ ? *last_position_stamp_s_ : -std::numeric_limits<double>::infinity();
}

double TargetTrack::lastOrientationStamp() const {
  return last_orientation_stamp_s_ ? *last_orientation_stamp_s_ : -std::numeric_limits<double>::infinity();
}

Eigen::Matrix<double, 2, 4> TargetTrack::positionJacobian() const {
  // p = c + R(psi) d: linear in (c, d) for the current yaw estimate.
  Eigen::Matrix<double, 2, 4> h = Eigen::Matrix<double, 2, 4>::Zero();
  h.leftCols<2>() = Eigen::Matrix2d::Identity();
  h.block<2, 2>(0, 2) = rotation(yaw_state_(0));
  return h;
}

void TargetTrack::propagate(double dt) {
  if (dt <= 0.0) return;
  Eigen::Matrix2d f;
  f << 1.0, dt, 0.0, 1.0;
  const double q = config_.yaw_rate_random_walk * config_.yaw_rate_random_walk;
  Eigen::Matrix2d qm;
  qm << q * dt * dt * dt / 3.0, q * dt * dt / 2.0, q * dt * dt / 2.0, q * dt;
  yaw_state_ = f * yaw_state_;
  yaw_state_(0) = wrapAngle(yaw_state_(0));
  yaw_cov_ = f * yaw_cov_ * f.transpose() + qm;
  // The centre and the offset stand still but for their random walks.
  const double qc = config_.centre_random_walk * config_.centre_random_walk * dt;
  const double qd = kOffsetRandomWalk * kOffsetRandomWalk * dt;
  Vector4d noise;
  noise << qc, qc, qd, qd;
  pos_cov_.diagonal() += noise;
}

void TargetTrack::restartPosition(const Vec2& measured, double variance) {
  // Keep the offset (the port is where it is on the target), move the centre under the measurement.
  const Vec2 offset = pos_state_.segment<2>(2);
  pos_state_.head<2>() = measured - rotation(yaw_state_(0)) * offset;
  pos_cov_.block<2, 4>(0, 0).setZero();
  pos_cov_.block<4, 2>(0, 0).setZero();
  pos_cov_.topLeftCorner<2, 2>() = Eigen::Matrix2d::Identity() * variance;
}

// Why an observation cannot be taken at all (empty reason: it can).
TrackUpdate TargetTrack::checkObservation(const TargetObservation& o) const {
  TrackUpdate result;
  if (!o.valid) {
    result.reason = o.status.empty() ? "estimate not valid" : "estimate not valid: " + o.status;
    return result;
  }
  if (!std::isfinite(o.stamp_s) || !std::isfinite(o.pose.x) || !std::isfinite(o.pose.y) ||
      (o.orientation_valid && !std::isfinite(o.pose.yaw)) ||
      !std::isfinite(o.position_sigma_m) || !std::isfinite(o.yaw_sigma_rad)) {
    result.reason = "estimate contains NaN or infinity";
    result.not_finite = true;
    return result;
  }
  if (last_position_stamp_s_ && o.stamp_s <= *last_position_stamp_s_) {
    result.reason = "estimate out of order (stamp not after the last one used)";
  }
  return result;
}

// The measurement's variances: its own sigmas or the defaults; the yaw's floored by range.
TargetTrack::MeasurementNoise TargetTrack::measurementNoise(const TargetObservation& o) const {
  MeasurementNoise noise;
  noise.position_var =
      std::pow(o.position_sigma_m > 0.0 ? o.position_sigma_m : kDefaultPositionSigmaM, 2);
  const double yaw_floor = std::isfinite(o.range_m) ? config_.yaw_sigma_per_range2 * o.range_m * o.range_m : 0.0;
  noise.yaw_var =
      std::pow(std::max(o.yaw_sigma_rad > 0.0 ? o.yaw_sigma_rad : kDefaultYawSigmaRad, yaw_floor), 2);
  return noise;
}

TrackUpdate TargetTrack::update(const TargetObservation& o) {
  TrackUpdate result = checkObservation(o);
  if (!result.reason.empty()) return result;
  const MeasurementNoise noise = measurementNoise(o);
  if (o.orientation_valid && !last_orientation_stamp_s_) {
    // The first orientation (the monocular pose, after position-only stereo estimates): start afresh
    // from it. The stereo positions are those of the target's blob, decimetres off the port, and
    // without a port axis the offset of the port from the turning centre could not be placed.
    last_position_stamp_s_.reset();
  }
  if (!last_position_stamp_s_) {
    start(o, noise);
    result.accepted = true;
    return result;
  }
  propagate(o.stamp_s - *last_position_stamp_s_);
  if (o.orientation_valid) result.reason = updateYaw(o, noise.yaw_var);
  yaw_state_(1) = clampAbs(yaw_state_(1), config_.max_port_yaw_rate_radps);
  if (!result.reason.empty()) return result;  // an outlier orientation: do not trust its position either
  result.reason = updatePosition(o.pose.position(), noise.position_var);
  if (!result.reason.empty()) return result;
  last_position_stamp_s_ = o.stamp_s;
  last_source_ = o.source;
  result.accepted = true;
  return result;
}

// First estimate: the centre behind the port by the prior offset (along the port axis; with no
// orientation yet the placeholder yaw 0), yaw rate unknown (prior).
void TargetTrack::start(const TargetObservation& o, const MeasurementNoise& noise) {
  const Vec2 measured = o.pose.position();
  yaw_state_ = Eigen::Vector2d(o.orientation_valid ? wrapAngle(o.pose.yaw) : 0.0, 0.0);
  yaw_cov_ = Eigen::Vector2d(o.orientation_valid ? noise.yaw_var : M_PI * M_PI,
                             std::pow(kInitialYawRateSigmaRadps, 2))
                 .asDiagonal();
  const Vec2 offset0 = rotation(yaw_state_(0)) * Vec2(config_.initial_offset_m, 0.0);
  pos_state_ << measured.x() - offset0.x(), measured.y() - offset0.y(), config_.initial_offset_m, 0.0;
  const double s0 = std::pow(config_.initial_offset_sigma_m, 2);
  pos_cov_.setZero();
  pos_cov_.diagonal() << noise.position_var + s0, noise.position_var + s0, s0, s0;
  // c + R d is known to the position variance: c and d are anti-correlated (d in the target frame, hence R).
  const Eigen::Matrix2d r = rotation(yaw_state_(0));
  pos_cov_.block<2, 2>(0, 2) = -s0 * r;
  pos_cov_.block<2, 2>(2, 0) = -s0 * r.transpose();
  if (o.orientation_valid) last_orientation_stamp_s_ = o.stamp_s;
  last_position_stamp_s_ = o.stamp_s;
  last_source_ = o.source;
}

// Filter 1 with a port axis; the first one after position-only estimates starts it afresh. Returns why the
// orientation was not taken (an outlier), or empty.
std::string TargetTrack::updateYaw(const TargetObservation& o, double yaw_var) {
  if (!last_orientation_stamp_s_) {
    // Until now the yaw was a placeholder: re-express the offset so the port stays where it was.
    const double new_yaw = wrapAngle(o.pose.yaw);
    const Eigen::Matrix2d change = rotation(new_yaw).transpose() * rotation(yaw_state_(0));
    pos_state_.segment<2>(2) = change * pos_state_.segment<2>(2);
    Matrix4d j = Matrix4d::Identity();
    j.block<2, 2>(2, 2) = change;
    pos_cov_ = j * pos_cov_ * j.transpose();
    yaw_state_(0) = new_yaw;
    yaw_cov_(0, 0) = yaw_var;
    yaw_cov_(0, 1) = yaw_cov_(1, 0) = 0.0;
    last_orientation_stamp_s_ = o.stamp_s;
    return "";
  }
  const double gate2 = config_.outlier_gate_sigma * config_.outlier_gate_sigma;
  const double innovation = wrapAngle(o.pose.yaw - yaw_state_(0));
  const double s = yaw_cov_(0, 0) + yaw_var;
  if (gate2 > 0.0 && innovation * innovation / s > gate2 && ++yaw_outliers_ < kOutlierResetCount) {
    return "orientation outlier (" + std::to_string(innovation) + " rad off the held one)";
  }
  if (yaw_outliers_ >= kOutlierResetCount) {
    yaw_state_(0) = wrapAngle(o.pose.yaw);  // it persisted: the target did turn; keep the rate
    yaw_cov_(0, 0) = yaw_var;
    yaw_cov_(0, 1) = yaw_cov_(1, 0) = 0.0;
  } else {
    const Eigen::Vector2d k = yaw_cov_.col(0) / s;
    yaw_state_ += k * innovation;
    yaw_state_(0) = wrapAngle(yaw_state_(0));
    yaw_cov_ -= k * yaw_cov_.row(0);
  }
  yaw_outliers_ = 0;
  last_orientation_stamp_s_ = o.stamp_s;
  return "";
}

// Filter 2; an outlier is refused (its reason returned) until it persists: then the centre restarts there.
std::string TargetTrack::updatePosition(const Vec2& measured, double position_var) {
  const double gate2 = config_.outlier_gate_sigma * config_.outlier_gate_sigma;
  const Eigen::Matrix<double, 2, 4> h = positionJacobian();
  const Vec2 innovation = measured - h * pos_state_;
  const Eigen::Matrix2d s = h * pos_cov_ * h.transpose() + Eigen::Matrix2d::Identity() * position_var;
  const double mahalanobis2 = innovation.dot(s.ldlt().solve(innovation));
  if (gate2 > 0.0 && mahalanobis2 > gate2) {
    if (++position_outliers_ < kOutlierResetCount) {
      return "position outlier (" + std::to_string(innovation.norm()) + " m off the held one)";
    }
    restartPosition(measured, position_var);  // it persisted: the target did move
  } else {
    const Eigen::Matrix<double, 4, 2> k = pos_cov_ * h.transpose() * s.inverse();
    pos_state_ += k * innovation;
    pos_cov_ = (Matrix4d::Identity() - k * h) * pos_cov_;
    pos_cov_ = 0.5 * (pos_cov_ + pos_cov_.transpose());
  }
  position_outliers_ = 0;
  return "";
}

PortState TargetTrack::predict(double now_s) const {
  PortState s;
  const double dt = last_position_stamp_s_ ? now_s - *last_position_stamp_s_ : 0.0;
  const double yaw_rate = yaw_state_(1);
  const double yaw = wrapAngle(yaw_state_(0) + yaw_rate * dt);
  const Vec2 offset = rotation(yaw) * pos_state_.segment<2>(2);
  const Vec2 position = pos_state_.head<2>() + offset;
  s.pose = Pose2D{position.x(), position.y(), yaw};
  s.yaw_rate = yaw_rate;
  s.velocity = clampNorm(yaw_rate * perpendicular(offset), config_.max_port_speed_mps);
  return s;
}

}  // namespace docking_planner
