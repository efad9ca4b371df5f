#include "omni_base/base_settings.h"

#include <docking_settings/setting_info.h>

#include <cmath>
#include <string>

#include "omni_base/motor_protocol.h"

namespace omni_base {

void validate(const OmniBaseSettings& s) {
  using docking_settings::ConfigError;
  using docking_settings::ConfigProblem;
  docking_settings::validateSettings(s);
  const std::size_t wheels = s.wheels.names.size();
  if (wheels == 0 || wheels > protocol::kMaxWheels) {
    throw ConfigError("wheels/names", ConfigProblem::kWrongSize,
                      "the motor protocol carries 1 to " + std::to_string(protocol::kMaxWheels) + " wheels, got " +
                          std::to_string(wheels));
  }
  if (s.wheels.drive_angles_deg.size() != wheels) {
    throw ConfigError("wheels/drive_angles_deg", ConfigProblem::kWrongSize,
                      "one per wheel name: " + std::to_string(wheels) + " expected, got " +
                          std::to_string(s.wheels.drive_angles_deg.size()));
  }
  if (s.serial.reconnect_backoff_max_s < s.serial.reconnect_backoff_min_s) {
    throw ConfigError("serial/reconnect_backoff_max_s", ConfigProblem::kInvalid,
                      "below serial/reconnect_backoff_min_s");
  }
}

WheelLayout wheelLayout(const WheelSettings& wheels) {
  WheelLayout layout;
  for (double degrees : wheels.drive_angles_deg) layout.drive_angles_rad.push_back(degrees * M_PI / 180.0);
  layout.center_distance_m = wheels.center_distance_m;
  layout.wheel_radius_m = wheels.radius_m;
  return layout;
}

MotorDriveModel driveModel(const MotorSettings& motor) {
  MotorDriveModel drive;
  drive.volts_per_rad_s = motor.volts_per_rad_s;
  drive.supply_volts = motor.supply_volts;
  return drive;
}

}  // namespace omni_base
