#include <gtest/gtest.h>

#include <cmath>
#include <fstream>
#include <sstream>

#include "omni_base/parameter_ranges.h"

using omni_base::checkParameterRange;
using omni_base::formatRange;
using omni_base::parameterRange;
using omni_base::parameterRanges;

// Issue 12: these values were accepted and defeated the watchdog / ate the CPU.
TEST(ParameterRanges, ValuesThatDefeatSafetyAreRefusedWithNameValueAndRange) {
  const auto timeout = checkParameterRange("watchdog/cmd_vel_timeout_s", 1e9, "/omni_base/watchdog/cmd_vel_timeout_s");
  ASSERT_TRUE(timeout);
  EXPECT_NE(timeout->find("/omni_base/watchdog/cmd_vel_timeout_s"), std::string::npos) << *timeout;
  EXPECT_NE(timeout->find("1e+09"), std::string::npos) << *timeout;
  EXPECT_NE(timeout->find("0.05 .. 2"), std::string::npos) << *timeout;
  EXPECT_TRUE(checkParameterRange("control_rate_hz", 1e9, "control_rate_hz"));
  EXPECT_TRUE(checkParameterRange("limits/stop_deceleration", 0.01, "x"));
  EXPECT_TRUE(checkParameterRange("encoders/max_plausible_speed_factor", 1e6, "x"));
  EXPECT_TRUE(checkParameterRange("serial/reconnect_backoff_max_s", 1e6, "x"));
  EXPECT_TRUE(checkParameterRange("serial/link_timeout_s", 0.0, "x"));
  EXPECT_TRUE(checkParameterRange("watchdog/cmd_vel_timeout_s", std::nan(""), "x"));
  EXPECT_TRUE(checkParameterRange("watchdog/cmd_vel_timeout_s", -1.0, "x"));
}

TEST(ParameterRanges, TheShippedDefaultsAreInRange) {
  const std::vector<std::pair<std::string, double>> defaults = {
      {"control_rate_hz", 50.0}, {"watchdog/cmd_vel_timeout_s", 0.5}, {"serial/link_timeout_s", 0.25},
      {"serial/reconnect_backoff_min_s", 0.1}, {"serial/reconnect_backoff_max_s", 2.0}, {"serial/baud", 115200},
      {"encoders/max_plausible_speed_factor", 2.0}, {"limits/stop_deceleration", 10.0}, {"limits/stop_deceleration", 30.0},
      {"limits/max_velocity", 1.5}, {"limits/max_acceleration", 3.0}, {"motor/time_constant_s", 0.02},
      {"motor/volts_per_rad_s", 0.55}, {"motor/supply_volts", 12.0}, {"wheels/radius_m", 0.024},
      {"wheels/center_distance_m", 0.10}, {"wheels/encoder_counts_per_rev", 1320}, {"wheels/encoder_bits", 32},
      {"wheels/drive_angles_deg", 240.0}};
  for (const auto& [name, value] : defaults) {
    const auto error = checkParameterRange(name, value, name);
    EXPECT_FALSE(error) << *error;
  }
}

TEST(ParameterRanges, EveryRangeIsSaneAndUnknownNamesThrow) {
  for (const auto& r : parameterRanges()) {
    EXPECT_LT(r.min, r.max) << r.name;
    EXPECT_FALSE(checkParameterRange(r.name, r.min, r.name)) << r.name;
    EXPECT_FALSE(checkParameterRange(r.name, r.max, r.name)) << r.name;
  }
  EXPECT_THROW(parameterRange("no/such_parameter"), std::out_of_range);
}

// One home per setting: the README's parameter table must show the range the loaders enforce.
TEST(ParameterRanges, ReadmeListsEveryRange) {
  std::ifstream readme(OMNI_BASE_README);
  ASSERT_TRUE(readme.good()) << OMNI_BASE_README;
  std::vector<std::string> lines;
  for (std::string line; std::getline(readme, line);) lines.push_back(line);
  for (const auto& r : parameterRanges()) {
    const std::string name = std::string("| `") + r.name + "` |";
    bool found = false;
    for (const auto& line : lines) {
      if (line.rfind(name, 0) == 0 && line.find(formatRange(r)) != std::string::npos) found = true;
    }
    EXPECT_TRUE(found) << "README.md has no row starting '" << name << "' with the range " << formatRange(r);
  }
}
