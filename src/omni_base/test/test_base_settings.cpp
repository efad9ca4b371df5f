// The base's settings (settings/omni_base.yaml): the shipped file passes, and values that defeat the
// safety functions are refused with their key (issue 12: a 1e9 s watchdog kept the wheels turning 5 s after
// the last command, and 1e9 Hz took 113 % CPU).
#include <docking_settings/yaml_loader.h>
#include <gtest/gtest.h>

#include "omni_base/base_settings.h"

using docking_settings::ConfigError;
using docking_settings::ConfigProblem;
using omni_base::OmniBaseSettings;

namespace {

OmniBaseSettings shipped() { return docking_settings::shippedSettings<OmniBaseSettings>(OMNI_BASE_CONFIG); }

/// The problem validate() reports for `settings`, with its key (nothing when it passes).
std::optional<std::pair<std::string, ConfigProblem>> problemOf(const OmniBaseSettings& settings) {
  try {
    omni_base::validate(settings);
  } catch (const ConfigError& e) {
    return std::make_pair(e.key(), e.problem());
  }
  return std::nullopt;
}

}  // namespace

TEST(BaseSettings, TheShippedBasePasses) {
  const OmniBaseSettings s = shipped();
  EXPECT_FALSE(problemOf(s));
  EXPECT_EQ(s.wheels.names.size(), 3u);
  EXPECT_DOUBLE_EQ(omni_base::driveModel(s.motor).maxSpeed(), 12.0 / 0.55);
  EXPECT_NEAR(omni_base::wheelLayout(s.wheels).drive_angles_rad[1], 2.0 * M_PI / 3.0, 1e-12);
}

TEST(BaseSettings, ValuesThatDefeatSafetyAreRefusedWithTheirKey) {
  OmniBaseSettings s = shipped();
  s.watchdog.cmd_vel_timeout_s = 1e9;
  EXPECT_EQ(problemOf(s), std::make_optional(std::make_pair(std::string("watchdog/cmd_vel_timeout_s"),
                                                            ConfigProblem::kOutOfRange)));
  s = shipped();
  s.control_rate_hz = 1e9;
  EXPECT_EQ(problemOf(s)->first, "control_rate_hz");
  s = shipped();
  s.limits.max_velocity[2] = 100.0;
  EXPECT_EQ(problemOf(s)->first, "limits/max_velocity");
  s = shipped();
  s.limits.stop_deceleration = {10.0, 10.0};
  EXPECT_EQ(problemOf(s)->second, ConfigProblem::kWrongSize);
}

TEST(BaseSettings, SettingsThatContradictAreRefused) {
  OmniBaseSettings s = shipped();
  s.wheels.drive_angles_deg.pop_back();
  EXPECT_EQ(problemOf(s), std::make_optional(std::make_pair(std::string("wheels/drive_angles_deg"),
                                                            ConfigProblem::kWrongSize)));
  s = shipped();
  s.wheels.names.assign(9, "w");
  s.wheels.drive_angles_deg.assign(9, 0.0);
  EXPECT_EQ(problemOf(s)->first, "wheels/names");
  s = shipped();
  s.serial.reconnect_backoff_min_s = 1.0;
  s.serial.reconnect_backoff_max_s = 0.5;
  EXPECT_EQ(problemOf(s), std::make_optional(std::make_pair(std::string("serial/reconnect_backoff_max_s"),
                                                            ConfigProblem::kInvalid)));
}
