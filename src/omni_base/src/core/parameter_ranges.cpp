#include "omni_base/parameter_ranges.h"

#include <cmath>
#include <sstream>
#include <stdexcept>

namespace omni_base {

const std::vector<ParameterRange>& parameterRanges() {
  // Issue 12: a 1e9 s watchdog kept the wheels turning 5 s after the last command and 1e9 Hz took
  // 113 % CPU. Upper bounds keep the safety functions meaningful; lower bounds keep them possible.
  static const std::vector<ParameterRange> kRanges = {
      {"control_rate_hz", 10.0, 200.0, "watchdog and stop ramps run at this rate; 200 Hz fills 115200 baud"},
      {"wheels/drive_angles_deg", -360.0, 360.0, "one turn either way"},
      {"wheels/center_distance_m", 0.02, 1.0, "a base this robot can be"},
      {"wheels/radius_m", 0.005, 0.25, "a wheel this robot can have"},
      {"wheels/encoder_counts_per_rev", 16.0, 1.0e6, "too few counts make the jump check meaningless"},
      {"wheels/encoder_bits", 8.0, 32.0, "the protocol carries 32-bit counters"},
      {"motor/volts_per_rad_s", 0.01, 10.0, "sets the maximum wheel speed, so every speed limit"},
      {"motor/supply_volts", 3.0, 48.0, "sets the maximum wheel speed, so every speed limit"},
      {"motor/time_constant_s", 0.001, 1.0, "fake board and simulator motor lag"},
      {"limits/max_velocity", 0.01, 3.0, "vx, vy m/s, wz rad/s"},
      {"limits/max_acceleration", 0.05, 10.0, "m/s^2, rad/s^2"},
      {"limits/stop_deceleration", 1.0, 100.0, "a softer stop lets the base coast on after a watchdog or e-stop"},
      {"watchdog/cmd_vel_timeout_s", 0.05, 2.0, "the base must stop soon after its commands stop"},
      {"serial/baud", 9600.0, 1000000.0, "and one the port supports"},
      {"serial/link_timeout_s", 0.05, 2.0, "a silent board must be noticed; below a few frames is noise"},
      {"serial/reconnect_backoff_min_s", 0.01, 5.0, "no busy reconnect loop"},
      {"serial/reconnect_backoff_max_s", 0.1, 60.0, "a returning board is found within a minute; >= the min"},
      {"encoders/max_plausible_speed_factor", 1.2, 10.0, "times the max wheel speed: a glitch must stand out"},
  };
  return kRanges;
}

const ParameterRange& parameterRange(const std::string& name) {
  for (const auto& r : parameterRanges()) {
    if (name == r.name) return r;
  }
  throw std::out_of_range("no range defined for parameter " + name);
}

std::string formatRange(const ParameterRange& range) {
  std::ostringstream out;
  out << range.min << " .. " << range.max;
  return out.str();
}

std::optional<std::string> checkParameterRange(const std::string& name, double value, const std::string& displayed_name) {
  const ParameterRange& range = parameterRange(name);
  if (std::isfinite(value) && value >= range.min && value <= range.max) return std::nullopt;
  std::ostringstream out;
  out << "parameter " << displayed_name << " = " << value << " is outside its allowed range " << formatRange(range)
      << " (" << range.why << ")";
  return out.str();
}

}  // namespace omni_base
