// The base's settings (settings/omni_base.yaml, config/omni_base.yaml) and what the cores take from them
// (ROS-free): one copy for the driver, the fake board, the firmware harness and the simulator.
#pragma once

#include "omni_base/kinematics.h"
#include "omni_base/motor.h"
#include "omni_base/omni_base_settings.h"

namespace omni_base {

/// Throws ConfigError (docking_settings) for a setting its declaration refuses, or settings that contradict
/// each other: a drive angle per wheel name, 1..8 wheels, the back-off's max not below its min.
void validate(const OmniBaseSettings& settings);

WheelLayout wheelLayout(const WheelSettings& wheels);
MotorDriveModel driveModel(const MotorSettings& motor);

}  // namespace omni_base
