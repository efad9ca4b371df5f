// Loads one nodelet into this process, for the camera executables that run without a nodelet manager.
#pragma once

#include <nodelet/loader.h>
#include <ros/ros.h>

#include <string>

namespace docking_perception {

inline int runNodeletStandalone(int argc, char** argv, const std::string& node_name, const std::string& type) {
  ros::init(argc, argv, node_name);
  nodelet::Loader loader(false);  // no load/unload services: this process runs just this nodelet
  const nodelet::M_string remappings(ros::names::getRemappings());
  // The nodelet sees the command line without the ROS remappings (those are passed separately).
  nodelet::V_string nodelet_argv;
  ros::removeROSArgs(argc, argv, nodelet_argv);
  if (!nodelet_argv.empty()) nodelet_argv.erase(nodelet_argv.begin());  // the program name
  // The nodelet logs why it did not start (e.g. the parameter that is missing).
  if (!loader.load(ros::this_node::getName(), type, remappings, nodelet_argv)) {
    ROS_FATAL("%s: could not start %s", ros::this_node::getName().c_str(), type.c_str());
    return 1;
  }
  ros::spin();
  return 0;
}

}  // namespace docking_perception
