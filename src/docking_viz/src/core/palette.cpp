#include "docking_viz/palette.h"

namespace docking_viz {

namespace {

// Indexed by EstimateSource. Hues far apart on the colour wheel and away from the grid's grey, so that
// two estimates side by side stay distinguishable; the fused one in the planner's blue.
const SourceStyle kSourceStyles[kSourceCount] = {
    {"disparity", "disparity", {1.0F, 0.55F, 0.0F, 1.0F}},        // orange
    {"mono visible", "mono_visible", {0.1F, 0.8F, 0.2F, 1.0F}},   // green
    {"mono IR", "mono_ir", {0.85F, 0.1F, 0.65F, 1.0F}},           // magenta
    {"fused", "fused", {0.15F, 0.55F, 1.0F, 1.0F}},               // blue
};
const SourceStyle kUnknownSourceStyle{"unknown", "unknown", {0.6F, 0.6F, 0.6F, 1.0F}};

}  // namespace

const SourceStyle& sourceStyle(std::uint8_t source) {
  return source < kSourceCount ? kSourceStyles[source] : kUnknownSourceStyle;
}

}  // namespace docking_viz
