// The monocular pose's pipeline: the stages MonoPoseEstimator::process() runs, in its order, and each
// stage's outcome codes (0: passed). TargetEstimate.stage / stage_outcome carry the stage that decided an
// estimate and its code, the node's diagnostics count them (README "mono_pose", "Stages"). The coarse
// category stays TargetEstimate.reject_reason (reject_reason.h).
//
// Which stage decides: the first that refuses the pose (valid = false); on a valid estimate, the position
// stage when it passed with the orientation claimed, or the orientation stage when the orientation is
// withheld (the position still valid).
#pragma once

#include <cstdint>

namespace docking_perception {
namespace mono {

enum class Stage : std::uint8_t {
  kNone = 0,          ///< not decided yet (never on the wire from this node)
  kInput = 1,         ///< the image (and, in the node, its camera_info) can be used
  kFind = 2,          ///< the target in the image: visible, the face (at its predicted place, by features, by
                      ///< its five printed dots, by direct alignment); IR, the pattern of five LED-like blobs
  kSolve = 3,         ///< the pose from those points: PnP (pnp) or the 5-point solver (paper_5point)
  kVet = 4,           ///< the pose against the image: the face's look, the dots
  kInnerPattern = 5,  ///< near contact, visible: the inner tag's pose when the face gave none
  kHint = 6,          ///< visible: the range against the disparity detector's estimate of the same target
  kOrientation = 7,   ///< the orientation claimed or withheld (the position stays valid)
  kTrack = 8,         ///< velocities, tracking state and the published (filtered) orientation: always passes
  kPosition = 9,      ///< the position claimed or withheld
};
constexpr Stage kLastStage = Stage::kPosition;

enum class InputOutcome : std::uint8_t {
  kPassed = 0,
  kEmpty,           ///< an empty image
  kWrongSize,       ///< not the size camera_info says
  kWrongType,       ///< neither 8-bit gray nor BGR
  kBadCameraInfo,   ///< (node) camera_info's projection is not a usable pinhole
  kNotConvertible,  ///< (node) cv_bridge cannot convert the encoding
  kDropped,         ///< (node) processing the image threw: dropped, the next one is processed
};

enum class FindOutcome : std::uint8_t {
  kPassed = 0,
  kFaceSearchSkipped,  ///< visible, near contact: the face's search skipped while the inner tag gives the pose
  kFaceNotFound,       ///< visible: no face at its predicted place, by features, by its dots or by direct alignment
  kNoLedPattern,       ///< IR: no five blobs form the pattern
  kLedBlobShape,       ///< IR: the patterns found have a blob merged with a reflection (size, elongation)
};

enum class SolveOutcome : std::uint8_t {
  kPassed = 0,
  kSolverFailed,   ///< no pose from the points (degenerate, IPPE failed; IR: no candidate gave one)
  kReprojection,   ///< RMS reprojection error above max_reprojection_px
  kImplausible,    ///< a range not finite, the back of the face, a covariance not finite
  kDotNotLocated,  ///< paper_5point: a printed dot not found where the face's homography puts it
};

enum class VetOutcome : std::uint8_t {
  kPassed = 0,
  kInlierSpread,        ///< the pose points cover less than min_inlier_spread of the face
  kAppearance,          ///< the model at the pose does not look like the image (min_appearance_ncc)
  kDotOffset,           ///< paper_5point: a located dot too far from the homography's prediction
  kSolverDisagreement,  ///< paper_5point: the 5-point pose and the face's PnP pose differ
};

enum class InnerPatternOutcome : std::uint8_t {
  kPassed = 0,
  kRetiredDisagreesWithFace,  ///< retired (the face/tag cross-check; numbers on the wire are never reused)
};

enum class HintOutcome : std::uint8_t {
  kPassed = 0,
  kRangeDisagrees,        ///< the range differs from a fresh disparity estimate's by max_hint_disagreement_fraction
  kHeldWithoutHint,       ///< within the hold (1 s) after a disagreement, no fresh estimate to check
  kNotRecovered,          ///< within that hold, not yet within half of max_hint_disagreement_fraction of a fresh estimate
};

enum class OrientationOutcome : std::uint8_t {
  kClaimed = 0,
  kAmbiguous,    ///< IPPE's two poses fit alike and differ by more than max_ambiguity_deg
  kRetiredJumps, ///< retired (a jump from the tracked orientation; numbers on the wire are never reused)
  kUnconfirmed,  ///< a first orientation, nothing to confirm it yet (confirm_new_orientation)
  kUncertain,    ///< its largest sigma is above max_rotation_sigma_deg
};

enum class PositionOutcome : std::uint8_t {
  kClaimed = 0,
  kUncertain,  ///< its largest sigma is above max_position_sigma_fraction of the range
};

/// A stage and its outcome code (0: passed).
struct StageOutcome {
  Stage stage = Stage::kNone;
  std::uint8_t code = 0;
  bool passed() const { return code == 0; }
};

template <typename Outcome>
StageOutcome outcomeOf(Stage stage, Outcome code) {
  return StageOutcome{stage, static_cast<std::uint8_t>(code)};
}

/// Short stable names ("find", "face_not_found"), for diagnostics and tables; "unknown" for a code the
/// stage does not have.
const char* stageName(Stage stage);
const char* outcomeName(Stage stage, std::uint8_t code);

}  // namespace mono
}  // namespace docking_perception
