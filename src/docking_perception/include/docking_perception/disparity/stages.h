// The disparity source's stages, in pipeline order, and each stage's outcome codes (ROS-free).
//
// Every estimate of perception/disparity/estimate carries the stage that decided it and its code there
// (TargetEstimate.stage, stage_outcome): the first stage that did not pass, or for a valid estimate the last
// stage with 0 (passed). The node checks the message (stage 1) and runs the detector (1-5,
// DisparityDetector::detect), the appearance check, the track gate and its own output check (6-8,
// DisparityDetectorNodelet::processDisparity); the package README draws them in this order. The numbers
// are on the wire: append codes, never renumber.
#pragma once

#include <cstdint>

namespace docking_perception {
namespace disparity {

enum class Stage : std::uint8_t {
  kInput = 1,          // the disparity image, its camera model and the searched region are usable
  kValidDisparity = 2, // enough valid disparities in the region, above the floor cut, filtered
  kBandSearch = 3,     // the nearest depth band holding a target-shaped blob (nearer bands looked behind)
  kPort = 4,           // the port from the mockup's footprint fitted to the blob's depth profile
  kPlausibility = 5,   // the blob's size, border and disparity range
  kAppearance = 6,     // the face print where the port is (node: the left image of the same stamp)
  kTrack = 7,          // agreement with the tracked target
  kOutput = 8,         // the estimate is well-formed (finite, a usable covariance) before it is published
};
constexpr int kStageCount = 8;

// Outcome codes per stage; 0 is "passed" (TargetEstimate.STAGE_PASSED) in every stage.
enum class InputOutcome : std::uint8_t {
  kPassed = 0,
  kBadEncoding = 1,         // not 32-bit float with one channel
  kEmptyImage = 2,          // no pixels
  kTruncatedData = 3,       // fewer bytes than its size and step need
  kWrongByteOrder = 4,      // is_bigendian differs from this machine's
  kBadGeometry = 5,         // focal length, baseline or principal point unusable
  kNoWindowCameraInfo = 6,  // a tracking window's disparity without its camera_info
  kEmptyRegion = 7,         // the matcher's valid window and the region of interest do not overlap
  kDropped = 8,             // processing threw: the image is dropped, the next one processed
};
enum class ValidDisparityOutcome : std::uint8_t {
  kPassed = 0,
  kTooFewValid = 1,         // fewer valid disparities than closest_min_pixels in the region
  kTooFewAfterFilter = 2,   // ...after the median filter
};
enum class BandSearchOutcome : std::uint8_t {
  kPassed = 0,
  kNoBlob = 1,              // nothing above the first threshold forms a blob
  kAllBlobsTooSmall = 2,    // every object in reach is smaller or thinner than a target
  kNotTargetShaped = 3,     // no blob in reach has the mockup's shape, height or isolation
};
enum class PortOutcome : std::uint8_t {
  kPassed = 0,
  kTooFewColumns = 1,       // too few image columns with depth to fit the footprint
};
enum class PlausibilityOutcome : std::uint8_t {
  kPassed = 0,
  kBlobTooSmall = 1,        // fewer valid pixels than min_blob_area_px
  kBlobTooThin = 2,         // thinner than min_blob_thickness_px
  kBlobTouchesBorder = 3,   // cut by the valid region's edge: its centre is not the target's
  // 4: retired (a blob too large for the searched region; numbers on the wire are never reused)
  kDisparityOutOfRange = 5, // robust disparity outside [min_disparity_px, max_disparity_px]
};
enum class AppearanceOutcome : std::uint8_t {
  kPassed = 0,              // matched, or not judged (too dark, no left image, outside the image)
  kMismatch = 1,            // the face print is not where the port is
  kGlare = 2,               // the face too saturated to judge: glare hides part of the mockup
};
enum class TrackOutcome : std::uint8_t {
  kPassed = 0,
  kOffTrack = 1,            // a jump from the tracked target, not yet confirmed
};
enum class OutputOutcome : std::uint8_t {
  kPassed = 0,
  kWithdrawn = 1,           // what the arbiter would refuse (a NaN, a bad covariance): withdrawn, not valid
};

constexpr Stage stageOf(InputOutcome) { return Stage::kInput; }
constexpr Stage stageOf(ValidDisparityOutcome) { return Stage::kValidDisparity; }
constexpr Stage stageOf(BandSearchOutcome) { return Stage::kBandSearch; }
constexpr Stage stageOf(PortOutcome) { return Stage::kPort; }
constexpr Stage stageOf(PlausibilityOutcome) { return Stage::kPlausibility; }
constexpr Stage stageOf(AppearanceOutcome) { return Stage::kAppearance; }
constexpr Stage stageOf(TrackOutcome) { return Stage::kTrack; }
constexpr Stage stageOf(OutputOutcome) { return Stage::kOutput; }

// The stage that decided and its code there.
struct StageOutcome {
  Stage stage = Stage::kInput;
  std::uint8_t code = 0;

  StageOutcome() = default;
  constexpr StageOutcome(Stage s, std::uint8_t c) : stage(s), code(c) {}
  template <typename Code>
  constexpr StageOutcome(Code c) : stage(stageOf(c)), code(static_cast<std::uint8_t>(c)) {}  // NOLINT: implicit

  bool passed() const { return code == 0; }
  bool operator==(const StageOutcome& other) const { return stage == other.stage && code == other.code; }
  bool operator!=(const StageOutcome& other) const { return !(*this == other); }
};

// Short stable names for diagnostics keys and logs: "band_search", "not_target_shaped" ("passed" for 0).
const char* stageName(Stage stage);
const char* outcomeName(StageOutcome outcome);

}  // namespace disparity
}  // namespace docking_perception
