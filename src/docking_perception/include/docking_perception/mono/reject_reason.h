// Why a monocular estimate is not valid: a code for programs (the arbiter, tests, the stress harness
// count by it) and MonoPoseResult::status for people. Behaviour is keyed on the code, never on the text.
#pragma once

#include <string>

namespace docking_perception {
namespace mono {

enum class RejectReason {
  kNone = 0,               // valid
  kBadInput,               // empty / wrong size / wrong type image
  kNotFound,               // no face match / no LED pattern
  kSolverFailed,           // the solver found no pose (degenerate points)
  kReprojection,           // residuals above max_reprojection_px
  kImplausiblePose,        // range not finite, back of the face, non-finite covariance
  kInlierSpread,           // the pose points bunched in a small part of the face (a wrong homography)
  kAppearance,             // the face does not look like the model at the estimated pose (NCC)
  kSolverDisagreement,     // two poses of one image disagree beyond their sigmas: the 5-point pose and the
                           // homography / PnP pose, or the face's pose and the inner pattern's
  kAmbiguous,              // (no longer given: an undecided IPPE pose keeps its position, orientation withheld)
  kLedBlobShape,           // IR: an LED blob merged / elongated / the wrong size for its range
  kDotAppearance,          // paper_5point: a located dot does not look like a printed dot
  // (12 is the arbiter's REJECT_SOURCES_SILENT, not an estimator's)
  kHintDisagreement = 13,  // visible: the range disagrees with the disparity detector's estimate of the
                           // same target (the position hint) by more than max_hint_disagreement_fraction
  kPositionUncertain = 14,  // the position's largest sigma is above max_position_sigma_fraction of the range
};

// Short stable name ("inlier_spread"), for tables and logs.
const char* toString(RejectReason reason);

}  // namespace mono
}  // namespace docking_perception
