// Loads one nodelet into this process, for the camera executables that run without a nodelet manager.
#pragma once

#include <docking_settings/config_error.h>
#include <docking_settings/run_node.h>
#include <nodelet/loader.h>
#include <ros/ros.h>

#include <string>

namespace docking_perception {

/// A nodelet that does not start (its onInit refused its settings, and said why) is a configuration error:
/// the process waits with it (docking_settings::runNode) instead of being respawned into it again.
inline int runNodeletStandalone(int argc, char** argv, const std::string& node_name, const std::string& type) {
  ros::init(argc, argv, node_name);
  return docking_settings::runNode([&] {
    nodelet::Loader loader(false);  // no load/unload services: this process runs just this nodelet
    const nodelet::M_string remappings(ros::names::getRemappings());
    // The nodelet sees the command line without the ROS remappings (those are passed separately).
    nodelet::V_string nodelet_argv;
    ros::removeROSArgs(argc, argv, nodelet_argv);
    if (!nodelet_argv.empty()) nodelet_argv.erase(nodelet_argv.begin());  // the program name
    if (!loader.load(ros::this_node::getName(), type, remappings, nodelet_argv)) {
      throw docking_settings::ConfigError(ros::this_node::getName(), docking_settings::ConfigProblem::kInvalid,
                                          type + " did not start (its own error is above)");
    }
    ros::spin();
  });
}

}  // namespace docking_perception
