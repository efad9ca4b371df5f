#include "docking_perception/mono/reject_reason.h"

namespace docking_perception {
namespace mono {

// The numbers are also docking_msgs/TargetEstimate's REJECT_* constants (the nodelet copies them):
// keep both lists in the same order.
const char* toString(RejectReason reason) {
  switch (reason) {
    case RejectReason::kNone: return "none";
    case RejectReason::kBadInput: return "bad_input";
    case RejectReason::kNotFound: return "not_found";
    case RejectReason::kSolverFailed: return "solver_failed";
    case RejectReason::kReprojection: return "reprojection";
    case RejectReason::kImplausiblePose: return "implausible_pose";
    case RejectReason::kInlierSpread: return "inlier_spread";
    case RejectReason::kAppearance: return "appearance";
    case RejectReason::kSolverDisagreement: return "solver_disagreement";
    case RejectReason::kAmbiguous: return "ambiguous";
    case RejectReason::kLedBlobShape: return "led_blob_shape";
    case RejectReason::kDotAppearance: return "dot_appearance";
    case RejectReason::kHintDisagreement: return "hint_disagreement";
    case RejectReason::kPositionUncertain: return "position_uncertain";
  }
  return "unknown";
}

}  // namespace mono
}  // namespace docking_perception
