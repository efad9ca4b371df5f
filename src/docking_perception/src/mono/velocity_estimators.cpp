#include "docking_perception/mono/velocity_estimators.h"

#include <Eigen/Cholesky>
#include <Eigen/LU>
#include <cmath>

namespace docking_perception {
namespace mono {
namespace {

// The velocity a (re)started filter assumes: zero, with these sigmas (a chaser's and a tumbling target's
// plausible rates); the next poses decide.
constexpr double kInitialVelocitySigma = 0.5;         // m/s
constexpr double kInitialAngularVelocitySigma = 1.0;  // rad/s

}  // namespace

void FrameDifferenceVelocity::reset() {
  has_previous_ = false;
  twist_ = TwistWithCovariance();
}

bool FrameDifferenceVelocity::update(double stamp_s, const PoseWithCovariance& pose, std::string* reason) {
  if (has_previous_ && !(stamp_s > previous_stamp_s_)) {
    if (reason) *reason = "pose stamp is not after the previous one";
    return false;
  }
  twist_ = TwistWithCovariance();
  if (has_previous_) {
    const double dt = stamp_s - previous_stamp_s_;
    if (dt <= max_gap_s_) {
      twist_.valid = true;
      twist_.linear = (pose.translation - previous_.translation) / dt;
      twist_.angular = rotationLog(pose.rotation * previous_.rotation.transpose()) / dt;
      // Difference of two independent estimates; the rotation difference is, to first order, the
      // difference of the two rotation errors.
      twist_.covariance = (pose.covariance + previous_.covariance) / (dt * dt);
    }
  }
  has_previous_ = true;
  previous_stamp_s_ = stamp_s;
  previous_ = pose;
  return true;
}

void ConstantVelocityFilter::reset() {
  initialized_ = false;
  updates_since_restart_ = 0;
  consecutive_rejections_ = 0;
}

void ConstantVelocityFilter::restart(double stamp_s, const PoseWithCovariance& pose) {
  initialized_ = true;
  updates_since_restart_ = 1;
  consecutive_rejections_ = 0;
  stamp_s_ = stamp_s;
  position_ = pose.translation;
  rotation_ = pose.rotation;
  velocity_.setZero();
  angular_velocity_.setZero();
  covariance_.setZero();
  covariance_.block<3, 3>(0, 0) = pose.covariance.block<3, 3>(0, 0);
  covariance_.block<3, 3>(0, 6) = pose.covariance.block<3, 3>(0, 3);
  covariance_.block<3, 3>(6, 0) = pose.covariance.block<3, 3>(3, 0);
  covariance_.block<3, 3>(6, 6) = pose.covariance.block<3, 3>(3, 3);
  const double sv = kInitialVelocitySigma;
  const double sw = kInitialAngularVelocitySigma;
  covariance_.block<3, 3>(3, 3) = Eigen::Matrix3d::Identity() * sv * sv;
  covariance_.block<3, 3>(9, 9) = Eigen::Matrix3d::Identity() * sw * sw;
}

void ConstantVelocityFilter::propagate(double dt, Eigen::Vector3d* position, Eigen::Matrix3d* rotation,
                                       Matrix12d* covariance) const {
  *position = position_ + velocity_ * dt;
  *rotation = rotationExp(angular_velocity_ * dt) * rotation_;
  Matrix12d transition = Matrix12d::Identity();
  transition.block<3, 3>(0, 3) = Eigen::Matrix3d::Identity() * dt;
  transition.block<3, 3>(6, 9) = Eigen::Matrix3d::Identity() * dt;
  // White-acceleration process noise of a constant-velocity model, per axis:
  // q * [[dt^3/3, dt^2/2], [dt^2/2, dt]].
  Matrix12d process = Matrix12d::Zero();
  const double dt2 = dt * dt;
  const double dt3 = dt2 * dt;
  for (int block = 0; block < 2; ++block) {
    const double q = block == 0 ? params_.accel_noise : params_.angular_accel_noise;
    const int offset = 6 * block;
    process.block<3, 3>(offset, offset) = Eigen::Matrix3d::Identity() * q * dt3 / 3.0;
    process.block<3, 3>(offset, offset + 3) = Eigen::Matrix3d::Identity() * q * dt2 / 2.0;
    process.block<3, 3>(offset + 3, offset) = Eigen::Matrix3d::Identity() * q * dt2 / 2.0;
    process.block<3, 3>(offset + 3, offset + 3) = Eigen::Matrix3d::Identity() * q * dt;
  }
  *covariance = transition * covariance_ * transition.transpose() + process;
}

bool ConstantVelocityFilter::update(double stamp_s, const PoseWithCovariance& pose, std::string* reason) {
  if (!initialized_) {
    restart(stamp_s, pose);
    return true;
  }
  const double dt = stamp_s - stamp_s_;
  if (!(dt > 0.0)) {
    if (reason) *reason = "pose stamp is not after the filter's last stamp (out of order)";
    return false;
  }
  if (dt > params_.max_gap_s) {
    restart(stamp_s, pose);
    if (reason) *reason = "gap of " + std::to_string(dt) + " s: filter restarted";
    return true;
  }
  Eigen::Vector3d predicted_position;
  Eigen::Matrix3d predicted_rotation;
  Matrix12d predicted_covariance;
  propagate(dt, &predicted_position, &predicted_rotation, &predicted_covariance);

  Vector6d innovation;
  innovation.head<3>() = pose.translation - predicted_position;
  innovation.tail<3>() = rotationLog(pose.rotation * predicted_rotation.transpose());
  Eigen::Matrix<double, 6, 12> observation = Eigen::Matrix<double, 6, 12>::Zero();
  observation.block<3, 3>(0, 0).setIdentity();
  observation.block<3, 3>(3, 6).setIdentity();
  // A tiny floor keeps S invertible when a solver reports an (unrealistically) exact pose.
  const Matrix6d measurement_covariance = pose.covariance + Matrix6d::Identity() * 1e-12;
  const Matrix6d innovation_covariance =
      observation * predicted_covariance * observation.transpose() + measurement_covariance;
  const Eigen::LDLT<Matrix6d> solver(innovation_covariance);
  const double chi2 = innovation.dot(solver.solve(innovation));
  if (params_.gate_chi2 > 0.0 && !(chi2 <= params_.gate_chi2)) {
    if (++consecutive_rejections_ >= kMaxConsecutiveRejections) {
      restart(stamp_s, pose);
      if (reason) *reason = "pose rejected " + std::to_string(kMaxConsecutiveRejections) + " times: filter restarted";
      return true;
    }
    if (reason) *reason = "pose rejected by the filter gate (chi2 " + std::to_string(chi2) + ")";
    return false;
  }
  consecutive_rejections_ = 0;
  const Eigen::Matrix<double, 12, 6> gain =
      predicted_covariance * observation.transpose() * innovation_covariance.inverse();
  const Eigen::Matrix<double, 12, 1> correction = gain * innovation;
  position_ = predicted_position + correction.segment<3>(0);
  velocity_ += correction.segment<3>(3);
  rotation_ = rotationExp(correction.segment<3>(6)) * predicted_rotation;
  angular_velocity_ += correction.segment<3>(9);
  // Joseph form: stays symmetric positive definite.
  const Matrix12d i_minus_kh = Matrix12d::Identity() - gain * observation;
  covariance_ = i_minus_kh * predicted_covariance * i_minus_kh.transpose() +
                gain * measurement_covariance * gain.transpose();
  stamp_s_ = stamp_s;
  ++updates_since_restart_;
  return true;
}

bool ConstantVelocityFilter::predict(double stamp_s, PoseWithCovariance* pose) const {
  if (!initialized_) return false;
  Eigen::Vector3d position;
  Eigen::Matrix3d rotation;
  Matrix12d covariance;
  propagate(std::max(0.0, stamp_s - stamp_s_), &position, &rotation, &covariance);
  pose->translation = position;
  pose->rotation = rotation;
  pose->covariance.block<3, 3>(0, 0) = covariance.block<3, 3>(0, 0);
  pose->covariance.block<3, 3>(0, 3) = covariance.block<3, 3>(0, 6);
  pose->covariance.block<3, 3>(3, 0) = covariance.block<3, 3>(6, 0);
  pose->covariance.block<3, 3>(3, 3) = covariance.block<3, 3>(6, 6);
  return true;
}

PoseWithCovariance ConstantVelocityFilter::pose() const {
  PoseWithCovariance result;
  predict(stamp_s_, &result);
  return result;
}

TwistWithCovariance ConstantVelocityFilter::twist() const {
  TwistWithCovariance twist;
  if (!initialized_ || updates_since_restart_ < 2) return twist;
  twist.valid = true;
  twist.linear = velocity_;
  twist.angular = angular_velocity_;
  twist.covariance.block<3, 3>(0, 0) = covariance_.block<3, 3>(3, 3);
  twist.covariance.block<3, 3>(0, 3) = covariance_.block<3, 3>(3, 9);
  twist.covariance.block<3, 3>(3, 0) = covariance_.block<3, 3>(9, 3);
  twist.covariance.block<3, 3>(3, 3) = covariance_.block<3, 3>(9, 9);
  return twist;
}

}  // namespace mono
}  // namespace docking_perception
