// The view's colours, defined once: one colour and one name per estimate source (every marker and label of
// a source uses them, so that a colour means the same thing everywhere in the view), and the colours of
// the planner's shapes. ROS-free.
#pragma once

#include <cstdint>

namespace docking_viz {

/// Numbered as docking_msgs/TargetEstimate's SOURCE_* constants (the node checks this at compile time).
enum class EstimateSource : std::uint8_t { kDisparity = 0, kMonoVisible = 1, kMonoIr = 2, kFused = 3 };
constexpr int kSourceCount = 4;

struct Rgba {
  float r{0.0F};
  float g{0.0F};
  float b{0.0F};
  float a{1.0F};
};

struct SourceStyle {
  const char* name;  ///< for people: "mono visible"
  const char* key;   ///< for marker namespaces: "mono_visible"
  Rgba colour;       ///< opaque; the node sets the alpha
};

// The planner's shapes: away from the sources' hues, so that a circle is never taken for an estimate.
constexpr Rgba kSafeCircleColour{1.0F, 0.9F, 0.1F, 0.9F};   // yellow: the line not to cross
constexpr Rgba kSearchOrbitColour{0.7F, 0.7F, 0.7F, 0.6F};  // grey: used only without a port axis
constexpr Rgba kPortAxisColour{1.0F, 1.0F, 1.0F, 0.9F};
constexpr Rgba kGoalColour{1.0F, 0.2F, 0.2F, 1.0F};         // red: where the chaser is going
constexpr Rgba kCommandColour{0.0F, 1.0F, 1.0F, 1.0F};      // cyan: the commanded velocity
constexpr Rgba kLabelColour{1.0F, 1.0F, 1.0F, 1.0F};

/// The style of a TargetEstimate source code; an unknown code gets a grey "unknown" style (a newer
/// producer's source must still be drawn, not crash the display).
const SourceStyle& sourceStyle(std::uint8_t source);

}  // namespace docking_viz
