#include "docking_perception/mono/stages.h"

#include <array>

namespace docking_perception {
namespace mono {
namespace {

template <std::size_t N>
const char* nameIn(const std::array<const char*, N>& names, std::uint8_t code) {
  return code < N ? names[code] : "unknown";
}

}  // namespace

const char* stageName(Stage stage) {
  static const std::array<const char*, 10> kNames = {"none",          "input", "find",        "solve", "vet",
                                                     "inner_pattern", "hint",  "orientation", "track", "position"};
  return nameIn(kNames, static_cast<std::uint8_t>(stage));
}

const char* outcomeName(Stage stage, std::uint8_t code) {
  static const std::array<const char*, 7> kInput = {"passed",           "empty",           "wrong_size", "wrong_type",
                                                    "bad_camera_info", "not_convertible", "dropped"};
  static const std::array<const char*, 5> kFind = {"passed", "face_search_skipped", "face_not_found", "no_led_pattern",
                                                   "led_blob_shape"};
  static const std::array<const char*, 5> kSolve = {"passed", "solver_failed", "reprojection", "implausible",
                                                    "dot_not_located"};
  static const std::array<const char*, 5> kVet = {"passed", "inlier_spread", "appearance", "dot_offset",
                                                  "solver_disagreement"};
  static const std::array<const char*, 2> kInnerPattern = {"passed", "retired"};
  static const std::array<const char*, 4> kHint = {"passed", "range_disagrees", "held_without_hint", "not_recovered"};
  static const std::array<const char*, 5> kOrientation = {"claimed", "ambiguous", "retired", "unconfirmed", "uncertain"};
  static const std::array<const char*, 2> kPosition = {"claimed", "uncertain"};
  static const std::array<const char*, 1> kPassedOnly = {"passed"};
  switch (stage) {
    case Stage::kInput: return nameIn(kInput, code);
    case Stage::kFind: return nameIn(kFind, code);
    case Stage::kSolve: return nameIn(kSolve, code);
    case Stage::kVet: return nameIn(kVet, code);
    case Stage::kInnerPattern: return nameIn(kInnerPattern, code);
    case Stage::kHint: return nameIn(kHint, code);
    case Stage::kOrientation: return nameIn(kOrientation, code);
    case Stage::kTrack: return nameIn(kPassedOnly, code);
    case Stage::kPosition: return nameIn(kPosition, code);
    case Stage::kNone: break;
  }
  return "unknown";
}

}  // namespace mono
}  // namespace docking_perception
