// Do two target estimates (in one common frame) describe the same pose? A chi-square test on their
// difference with both covariances, plus what the target may have moved between the two stamps and
// the uncertainty of the camera mounts (ROS-free). Used by SourceArbiter to keep a confidently wrong
// source from being published when another source contradicts it.
#pragma once

#include <optional>

#include "docking_perception/arbiter/frame_change.h"

namespace docking_perception {
namespace arbiter {

/// Settings of the cross-source consistency check (config/arbiter.yaml, `consistency_*`).
struct ConsistencyConfig {
  bool enabled{true};
  double gate_chi2_pose{22.46};      ///< 6-dof test (mono vs mono): chi-square 99.9 % quantile, 6 dof
  double gate_chi2_position{16.27};  ///< 3-dof test (position only): chi-square 99.9 % quantile, 3 dof
  double stamp_tolerance_s{0.05};    ///< estimates further apart in time are not compared
  double min_speed_mps{0.05};        ///< floor of the relative speed used for the stamp allowance
  double min_rate_radps{0.05};       ///< floor of the relative turn rate used for the stamp allowance
  double mount_sigma_m{0.005};       ///< camera mount calibration, per axis (also keeps the test defined
  double mount_sigma_rad{0.01};      ///<   when a source reports a zero covariance)
};

/// Throws std::invalid_argument naming the bad field (prefixed "consistency_").
void validate(const ConsistencyConfig& config);

/// One estimate as the test needs it: its pose in the common frame, its stamp, and its velocity
/// relative to the camera when known (for how far it may have moved between two stamps).
struct ComparablePose {
  double stamp_s{0.0};
  PoseWithCovariance3 pose;
  bool has_orientation{false};
  double speed_mps{0.0};    ///< |v| of the estimate's own twist, 0 when unknown
  double rate_radps{0.0};   ///< |w| of the estimate's own twist, 0 when unknown
};

struct ConsistencyTest {
  int dof{0};            ///< 6: position and orientation; 3: position only
  double chi2{0.0};      ///< squared Mahalanobis distance of the difference
  double gate{0.0};      ///< the chi-square gate for `dof`
  double dt_s{0.0};      ///< |stamp difference|
  bool agree{true};      ///< chi2 <= gate
};

/// Compares `a` and `b`: position and orientation when both have an orientation, position only
/// otherwise. Returns nothing when the covariances of the compared components are not finite (the
/// test would mean nothing). The stamp difference is NOT checked here (see SourceArbiter), so that
/// the previous output, older than the stamp tolerance, can be compared too.
std::optional<ConsistencyTest> compare(const ComparablePose& a, const ComparablePose& b,
                                       const ConsistencyConfig& config);

}  // namespace arbiter
}  // namespace docking_perception
