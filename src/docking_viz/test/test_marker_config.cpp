// validate(MarkerConfig): the defaults pass; a bad value is refused with its parameter's name.
#include <gtest/gtest.h>

#include <cmath>
#include <functional>
#include <stdexcept>
#include <string>

#include "docking_viz/marker_config.h"

using namespace docking_viz;

namespace {

// The message of the exception validate() throws for `config`, or "" when it accepts it.
std::string refusal(const MarkerConfig& config) {
  try {
    validate(config);
  } catch (const std::invalid_argument& e) {
    return e.what();
  }
  return "";
}

}  // namespace

TEST(MarkerConfig, DefaultsAreValid) { EXPECT_EQ(refusal(MarkerConfig{}), ""); }

TEST(MarkerConfig, RefusesBadValuesByName) {
  const std::pair<std::string, std::function<void(MarkerConfig*)>> cases[] = {
      {"publish_rate_hz", [](MarkerConfig* c) { c->publish_rate_hz = 0.0; }},
      {"marker_lifetime_s", [](MarkerConfig* c) { c->marker_lifetime_s = -1.0; }},
      {"input_timeout_s", [](MarkerConfig* c) { c->input_timeout_s = std::nan(""); }},
      {"sigma_scale", [](MarkerConfig* c) { c->sigma_scale = INFINITY; }},
      {"circle_segments", [](MarkerConfig* c) { c->circle_segments = 3; }},
      {"text_offset_z_m", [](MarkerConfig* c) { c->text_offset_z_m = std::nan(""); }},
      {"planner_namespace", [](MarkerConfig* c) { c->planner_namespace.clear(); }},
  };
  for (const auto& [name, spoil] : cases) {
    MarkerConfig config;
    spoil(&config);
    EXPECT_NE(refusal(config).find(name), std::string::npos) << name << ": " << refusal(config);
  }
}
