// How every node of the workspace starts and stops on an error. A configuration error (ConfigError) is
// reported once, FATAL, naming the node and the key; then the node stays up doing nothing, its
// diagnostics ERROR naming the key, until it is shut down. Respawning it (roslaunch respawn="true")
// would repeat the same error forever, and a node that commands nothing is safe: the base stops on its
// own watchdog. Any other exception is a failure at run time: FATAL, exit 1, and roslaunch respawns it.
#pragma once

#include <functional>

namespace docking_settings {

constexpr int kExitRuntimeFailure = 1;

/// Runs `body` (construct the node and spin); call after ros::init. Returns the process's exit code.
int runNode(const std::function<void()>& body);

}  // namespace docking_settings
