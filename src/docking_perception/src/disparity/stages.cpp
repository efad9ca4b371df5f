#include "docking_perception/disparity/stages.h"

namespace docking_perception {
namespace disparity {

const char* stageName(Stage stage) {
  switch (stage) {
    case Stage::kInput: return "input";
    case Stage::kValidDisparity: return "valid_disparity";
    case Stage::kBandSearch: return "band_search";
    case Stage::kPort: return "port";
    case Stage::kPlausibility: return "plausibility";
    case Stage::kAppearance: return "appearance";
    case Stage::kTrack: return "track";
    case Stage::kOutput: return "output";
  }
  return "unknown";
}

namespace {

const char* inputName(InputOutcome code) {
  switch (code) {
    case InputOutcome::kPassed: return "passed";
    case InputOutcome::kBadEncoding: return "bad_encoding";
    case InputOutcome::kEmptyImage: return "empty_image";
    case InputOutcome::kTruncatedData: return "truncated_data";
    case InputOutcome::kWrongByteOrder: return "wrong_byte_order";
    case InputOutcome::kBadGeometry: return "bad_geometry";
    case InputOutcome::kNoWindowCameraInfo: return "no_window_camera_info";
    case InputOutcome::kEmptyRegion: return "empty_region";
    case InputOutcome::kDropped: return "dropped";
  }
  return "unknown";
}

const char* validDisparityName(ValidDisparityOutcome code) {
  switch (code) {
    case ValidDisparityOutcome::kPassed: return "passed";
    case ValidDisparityOutcome::kTooFewValid: return "too_few_valid";
    case ValidDisparityOutcome::kTooFewAfterFilter: return "too_few_after_filter";
  }
  return "unknown";
}

const char* bandSearchName(BandSearchOutcome code) {
  switch (code) {
    case BandSearchOutcome::kPassed: return "passed";
    case BandSearchOutcome::kNoBlob: return "no_blob";
    case BandSearchOutcome::kAllBlobsTooSmall: return "all_blobs_too_small";
    case BandSearchOutcome::kNotTargetShaped: return "not_target_shaped";
  }
  return "unknown";
}

const char* portName(PortOutcome code) {
  switch (code) {
    case PortOutcome::kPassed: return "passed";
    case PortOutcome::kTooFewColumns: return "too_few_columns";
  }
  return "unknown";
}

const char* plausibilityName(PlausibilityOutcome code) {
  switch (code) {
    case PlausibilityOutcome::kPassed: return "passed";
    case PlausibilityOutcome::kBlobTooSmall: return "blob_too_small";
    case PlausibilityOutcome::kBlobTooThin: return "blob_too_thin";
    case PlausibilityOutcome::kBlobTouchesBorder: return "blob_touches_border";
    case PlausibilityOutcome::kDisparityOutOfRange: return "disparity_out_of_range";
  }
  return "unknown";
}

const char* appearanceName(AppearanceOutcome code) {
  switch (code) {
    case AppearanceOutcome::kPassed: return "passed";
    case AppearanceOutcome::kMismatch: return "appearance_mismatch";
    case AppearanceOutcome::kGlare: return "appearance_glare";
  }
  return "unknown";
}

const char* trackName(TrackOutcome code) {
  switch (code) {
    case TrackOutcome::kPassed: return "passed";
    case TrackOutcome::kOffTrack: return "off_track";
  }
  return "unknown";
}

const char* outputName(OutputOutcome code) {
  switch (code) {
    case OutputOutcome::kPassed: return "passed";
    case OutputOutcome::kWithdrawn: return "withdrawn";
  }
  return "unknown";
}

}  // namespace

const char* outcomeName(StageOutcome outcome) {
  switch (outcome.stage) {
    case Stage::kInput: return inputName(static_cast<InputOutcome>(outcome.code));
    case Stage::kValidDisparity: return validDisparityName(static_cast<ValidDisparityOutcome>(outcome.code));
    case Stage::kBandSearch: return bandSearchName(static_cast<BandSearchOutcome>(outcome.code));
    case Stage::kPort: return portName(static_cast<PortOutcome>(outcome.code));
    case Stage::kPlausibility: return plausibilityName(static_cast<PlausibilityOutcome>(outcome.code));
    case Stage::kAppearance: return appearanceName(static_cast<AppearanceOutcome>(outcome.code));
    case Stage::kTrack: return trackName(static_cast<TrackOutcome>(outcome.code));
    case Stage::kOutput: return outputName(static_cast<OutputOutcome>(outcome.code));
  }
  return "unknown";
}

}  // namespace disparity
}  // namespace docking_perception
