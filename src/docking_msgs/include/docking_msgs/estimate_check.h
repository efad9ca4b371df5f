// Checks of a TargetEstimate before any code trusts it (ROS-free: plain numbers in, a code out). One copy,
// used by the arbiter (docking_perception) and the planner (docking_planner), which both take estimates
// from other processes: a stamp far in the future, a NaN or a zero quaternion must not reach their state.
// estimate_check_msg.h fills EstimateFields from the message.
#pragma once

#include <array>
#include <cstdint>
#include <optional>

namespace docking_msgs {
namespace checks {

/// |‖q‖ - 1| above this: the orientation is not a rotation (a zero quaternion is 1 off). Estimators
/// publish normalised quaternions; 0.01 leaves room for float rounding and a hand-written test message.
constexpr double kUnitQuaternionTolerance = 0.01;
/// Relative tolerance of a covariance's symmetry (|a_ij - a_ji| <= tol * max(1, |a_ij|, |a_ji|)): a
/// frame change leaves rounding of ~1e-16 relative; 1e-6 only catches a wrong matrix.
constexpr double kCovarianceSymmetryTolerance = 1e-6;
/// The clock has jumped back (sim time reset, bag loop) when `now` falls more than this below the
/// latest `now` seen: ordering state is then reset. Small steps back (NTP) are left alone.
constexpr double kClockJumpBackS = 0.5;

/// Why a stamp is refused, as a code (programs key on it; stampProblemName() is for people).
enum class StampProblem : std::uint8_t {
  kNone = 0,
  kNotFinite = 1,  ///< NaN or infinite
  kFuture = 2,     ///< more than max_future_s ahead of now
  kTooOld = 3,     ///< more than max_age_s behind now
  kUnset = 4,      ///< exactly 0: ROS's "no stamp" (it passed as recent while a sim clock was under max_age_s)
};
const char* stampProblemName(StampProblem problem);

struct StampLimits {
  double max_future_s{0.5};  ///< clock skew between computers and the stamping latency of a camera
  double max_age_s{5.0};     ///< older than this: nothing a pipeline of ~100 ms latency produces
};
/// The limits every node that takes estimates from another process uses (the arbiter, the planner):
/// constants, not settings.
inline constexpr StampLimits kStampLimits{};

StampProblem checkStamp(double stamp_s, double now_s, const StampLimits& limits);

/// Why an estimate's numbers are refused, as a code. The whole estimate is refused (not only the bad
/// part): a producer that writes a zero quaternion or a NaN is broken, and its other numbers are suspect.
enum class EstimateProblem : std::uint8_t {
  kNone = 0,
  kPositionNotFinite = 1,
  kOrientationNotFinite = 2,
  kOrientationNotUnit = 3,           ///< |‖q‖ - 1| > kUnitQuaternionTolerance (a zero quaternion)
  kPoseCovarianceNotFinite = 4,
  kPoseCovarianceNotSymmetric = 5,
  kPoseCovarianceNegativeVariance = 6,
  kTwistNotFinite = 7,
  kTwistCovarianceNotFinite = 8,
  kTwistCovarianceNotSymmetric = 9,
  kTwistCovarianceNegativeVariance = 10,
  kRangeNotFinite = 11,
  kNoFrameId = 12,  ///< header.frame_id empty: nothing could place it (tf2 refuses an empty frame)
};
const char* estimateProblemName(EstimateProblem problem);

/// The numbers of a TargetEstimate (docking_msgs/TargetEstimate.msg), without the message type.
struct EstimateFields {
  bool has_frame_id{true};  ///< header.frame_id not empty; checked for every estimate, valid or not
  bool valid{false};
  bool position_valid{false};
  bool orientation_valid{false};
  bool twist_valid{false};
  std::array<double, 3> position{};
  std::array<double, 4> orientation_xyzw{0.0, 0.0, 0.0, 1.0};
  std::array<double, 36> pose_covariance{};
  std::array<double, 6> twist{};  ///< linear x, y, z, angular x, y, z
  std::array<double, 36> twist_covariance{};
  double range_m{0.0};
};

/// A frame for every estimate; then checks what the flags claim: nothing more for an invalid estimate (its numbers are undefined by the
/// message's definition); the position, the orientation (finite, unit norm), the pose covariance and
/// the range of a valid one; the twist and its covariance when twist_valid. The first problem found.
EstimateProblem checkEstimateFields(const EstimateFields& fields);

enum class CovarianceProblem : std::uint8_t { kNone, kNotFinite, kNotSymmetric, kNegativeVariance };
CovarianceProblem checkCovariance(const std::array<double, 36>& row_major_6x6);

/// Odometry (nav_msgs/Odometry of the chaser's base) beyond these is not a robot on a test floor: a
/// broken or hostile publisher. Far above anything true (a floor is ~10 m, the base's limits ~1 m/s,
/// a few rad/s), so only garbage is refused.
constexpr double kMaxOdometryPositionM = 1000.0;
constexpr double kMaxOdometrySpeedMps = 10.0;
constexpr double kMaxOdometryTurnRateRadps = 50.0;

/// Why an odometry message is refused, as a code (odometryProblemName() is for people).
enum class OdometryProblem : std::uint8_t {
  kNone = 0,
  kPositionNotFinite = 1,
  kPositionOutOfBounds = 2,  ///< |x| or |y| or |z| above kMaxOdometryPositionM
  kOrientationNotFinite = 3,
  kOrientationNotUnit = 4,   ///< |‖q‖ - 1| > kUnitQuaternionTolerance
  kTwistNotFinite = 5,
  kTwistOutOfBounds = 6,     ///< planar speed or turn rate above the bounds above
};
const char* odometryProblemName(OdometryProblem problem);

struct OdometryFields {
  std::array<double, 3> position{};
  std::array<double, 4> orientation_xyzw{0.0, 0.0, 0.0, 1.0};
  std::array<double, 6> twist{};  ///< linear x, y, z, angular x, y, z (child frame)
};
/// The first problem found; the stamp is checked apart (checkStamp).
OdometryProblem checkOdometryFields(const OdometryFields& fields);

/// Detects the clock jumping back (sim time reset, a bag replayed in a loop): ordering state built on
/// the old timeline (the latest stamp per source) would otherwise refuse every new estimate.
class ClockJumpDetector {
 public:
  /// True when `now_s` lies more than kClockJumpBackS below the latest `now` seen (which then
  /// becomes `now_s`).
  bool jumpedBack(double now_s);

 private:
  std::optional<double> latest_now_s_;
};

}  // namespace checks
}  // namespace docking_msgs
