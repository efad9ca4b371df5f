#include "docking_msgs/estimate_check.h"

#include <algorithm>
#include <cmath>

namespace docking_msgs {
namespace checks {
namespace {

template <std::size_t N>
bool allFinite(const std::array<double, N>& values) {
  return std::all_of(values.begin(), values.end(), [](double x) { return std::isfinite(x); });
}

bool isUnitQuaternion(const std::array<double, 4>& q) {
  const double norm = std::sqrt(q[0] * q[0] + q[1] * q[1] + q[2] * q[2] + q[3] * q[3]);
  return std::abs(norm - 1.0) <= kUnitQuaternionTolerance;
}

EstimateProblem pick(CovarianceProblem problem, EstimateProblem not_finite, EstimateProblem not_symmetric,
                     EstimateProblem negative) {
  switch (problem) {
    case CovarianceProblem::kNone:
      return EstimateProblem::kNone;
    case CovarianceProblem::kNotFinite:
      return not_finite;
    case CovarianceProblem::kNotSymmetric:
      return not_symmetric;
    case CovarianceProblem::kNegativeVariance:
      return negative;
  }
  return not_finite;
}

}  // namespace

const char* stampProblemName(StampProblem problem) {
  switch (problem) {
    case StampProblem::kNone:
      return "none";
    case StampProblem::kNotFinite:
      return "stamp_not_finite";
    case StampProblem::kFuture:
      return "stamp_in_future";
    case StampProblem::kTooOld:
      return "stamp_too_old";
    case StampProblem::kUnset:
      return "stamp_unset";
  }
  return "unknown";
}

const char* estimateProblemName(EstimateProblem problem) {
  switch (problem) {
    case EstimateProblem::kNone:
      return "none";
    case EstimateProblem::kPositionNotFinite:
      return "position_not_finite";
    case EstimateProblem::kOrientationNotFinite:
      return "orientation_not_finite";
    case EstimateProblem::kOrientationNotUnit:
      return "orientation_not_unit_quaternion";
    case EstimateProblem::kPoseCovarianceNotFinite:
      return "pose_covariance_not_finite";
    case EstimateProblem::kPoseCovarianceNotSymmetric:
      return "pose_covariance_not_symmetric";
    case EstimateProblem::kPoseCovarianceNegativeVariance:
      return "pose_covariance_negative_variance";
    case EstimateProblem::kTwistNotFinite:
      return "twist_not_finite";
    case EstimateProblem::kTwistCovarianceNotFinite:
      return "twist_covariance_not_finite";
    case EstimateProblem::kTwistCovarianceNotSymmetric:
      return "twist_covariance_not_symmetric";
    case EstimateProblem::kTwistCovarianceNegativeVariance:
      return "twist_covariance_negative_variance";
    case EstimateProblem::kRangeNotFinite:
      return "range_not_finite";
    case EstimateProblem::kNoFrameId:
      return "no_frame_id";
  }
  return "unknown";
}

StampProblem checkStamp(double stamp_s, double now_s, const StampLimits& limits) {
  if (!std::isfinite(stamp_s)) return StampProblem::kNotFinite;
  if (stamp_s == 0.0) return StampProblem::kUnset;
  if (stamp_s - now_s > limits.max_future_s) return StampProblem::kFuture;
  if (now_s - stamp_s > limits.max_age_s) return StampProblem::kTooOld;
  return StampProblem::kNone;
}

CovarianceProblem checkCovariance(const std::array<double, 36>& m) {
  if (!allFinite(m)) return CovarianceProblem::kNotFinite;
  for (std::size_t r = 0; r < 6; ++r) {
    if (m[r * 6 + r] < 0.0) return CovarianceProblem::kNegativeVariance;
    for (std::size_t c = r + 1; c < 6; ++c) {
      const double a = m[r * 6 + c];
      const double b = m[c * 6 + r];
      const double scale = std::max({1.0, std::abs(a), std::abs(b)});
      if (std::abs(a - b) > kCovarianceSymmetryTolerance * scale) return CovarianceProblem::kNotSymmetric;
    }
  }
  return CovarianceProblem::kNone;
}

EstimateProblem checkEstimateFields(const EstimateFields& f) {
  if (!f.has_frame_id) return EstimateProblem::kNoFrameId;
  if (!f.valid) return EstimateProblem::kNone;
  if (f.position_valid && !allFinite(f.position)) return EstimateProblem::kPositionNotFinite;
  if (f.orientation_valid) {
    if (!allFinite(f.orientation_xyzw)) return EstimateProblem::kOrientationNotFinite;
    if (!isUnitQuaternion(f.orientation_xyzw)) return EstimateProblem::kOrientationNotUnit;
  }
  if (f.position_valid || f.orientation_valid) {
    const EstimateProblem p = pick(checkCovariance(f.pose_covariance), EstimateProblem::kPoseCovarianceNotFinite,
                                   EstimateProblem::kPoseCovarianceNotSymmetric,
                                   EstimateProblem::kPoseCovarianceNegativeVariance);
    if (p != EstimateProblem::kNone) return p;
  }
  if (f.position_valid && !std::isfinite(f.range_m)) return EstimateProblem::kRangeNotFinite;
  if (f.twist_valid) {
    if (!allFinite(f.twist)) return EstimateProblem::kTwistNotFinite;
    return pick(checkCovariance(f.twist_covariance), EstimateProblem::kTwistCovarianceNotFinite,
                EstimateProblem::kTwistCovarianceNotSymmetric, EstimateProblem::kTwistCovarianceNegativeVariance);
  }
  return EstimateProblem::kNone;
}

bool ClockJumpDetector::jumpedBack(double now_s) {
  const bool jumped = latest_now_s_ && now_s < *latest_now_s_ - kClockJumpBackS;
  if (!latest_now_s_ || jumped || now_s > *latest_now_s_) latest_now_s_ = now_s;
  return jumped;
}

const char* odometryProblemName(OdometryProblem problem) {
  switch (problem) {
    case OdometryProblem::kNone:
      return "none";
    case OdometryProblem::kPositionNotFinite:
      return "odometry_position_not_finite";
    case OdometryProblem::kPositionOutOfBounds:
      return "odometry_position_out_of_bounds";
    case OdometryProblem::kOrientationNotFinite:
      return "odometry_orientation_not_finite";
    case OdometryProblem::kOrientationNotUnit:
      return "odometry_orientation_not_unit";
    case OdometryProblem::kTwistNotFinite:
      return "odometry_twist_not_finite";
    case OdometryProblem::kTwistOutOfBounds:
      return "odometry_twist_out_of_bounds";
  }
  return "unknown";
}

OdometryProblem checkOdometryFields(const OdometryFields& fields) {
  if (!allFinite(fields.position)) return OdometryProblem::kPositionNotFinite;
  for (double p : fields.position) {
    if (std::abs(p) > kMaxOdometryPositionM) return OdometryProblem::kPositionOutOfBounds;
  }
  if (!allFinite(fields.orientation_xyzw)) return OdometryProblem::kOrientationNotFinite;
  if (!isUnitQuaternion(fields.orientation_xyzw)) return OdometryProblem::kOrientationNotUnit;
  if (!allFinite(fields.twist)) return OdometryProblem::kTwistNotFinite;
  if (std::hypot(fields.twist[0], fields.twist[1]) > kMaxOdometrySpeedMps ||
      std::abs(fields.twist[5]) > kMaxOdometryTurnRateRadps) {
    return OdometryProblem::kTwistOutOfBounds;
  }
  return OdometryProblem::kNone;
}

}  // namespace checks
}  // namespace docking_msgs
