// Do two target estimates (in one common frame) describe the same pose? A chi-square test on their
// difference with both covariances, plus what the target may have moved between the two stamps and
// the uncertainty of the camera mounts (ROS-free). Used by SourceArbiter to keep a confidently wrong
// source from being published when another source contradicts it.
#pragma once

#include <optional>

#include "docking_perception/arbiter/arbiter_settings.h"
#include "docking_perception/arbiter/frame_change.h"

namespace docking_perception {
namespace arbiter {

/// ConsistencyConfig, the check's settings, is declared in settings/arbiter.yaml (generated header).

/// Throws std::invalid_argument (ConfigError) naming the first setting its declaration does not allow.
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
