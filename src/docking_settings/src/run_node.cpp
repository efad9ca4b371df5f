#include "docking_settings/run_node.h"

#include <diagnostic_updater/diagnostic_updater.h>
#include <ros/ros.h>
#include <rosgraph_msgs/Log.h>

#include <csignal>

#include "docking_settings/config_error.h"

namespace docking_settings {
namespace {

void shutDownOnSigint(int) { ros::requestShutdown(); }  // as roscpp's own handler (a node may have replaced it)

/// Stays up, commanding nothing, with a diagnostics ERROR that names the key, until shut down.
void waitWithTheError(const ConfigError& error) {
  std::signal(SIGINT, shutDownOnSigint);
  ros::NodeHandle nh;
  diagnostic_updater::Updater diagnostics;
  diagnostics.setHardwareID("none");
  diagnostics.add("Configuration", [&error](diagnostic_updater::DiagnosticStatusWrapper& stat) {
    stat.summaryf(diagnostic_msgs::DiagnosticStatus::ERROR, "configuration error: %s", error.what());
    stat.add("key", error.key());
    stat.add("problem", configProblemName(error.problem()));
  });
  const ros::WallTimer tick = nh.createWallTimer(ros::WallDuration(1.0), [&diagnostics](const ros::WallTimerEvent&) {
    diagnostics.force_update();
  });
  diagnostics.force_update();
  ros::spin();
}

/// Waits (up to `limit`) until /rosout listens to this node: a message logged before is printed but never
/// reaches /rosout (rqt_console, rosout.log), and a configuration error is logged only once.
void waitForRosout(ros::WallDuration limit) {
  ros::NodeHandle nh;
  const ros::Publisher rosout = nh.advertise<rosgraph_msgs::Log>("/rosout", 1);  // the node's own publication
  const ros::WallTime deadline = ros::WallTime::now() + limit;
  while (ros::ok() && rosout.getNumSubscribers() == 0 && ros::WallTime::now() < deadline) {
    ros::WallDuration(0.02).sleep();
  }
}

}  // namespace

int runNode(const std::function<void()>& body) {
  // Started here, outside the body: the body's node handles die with the exception, and the last node
  // handle going shuts roscpp down, rosconsole with it, so that the FATAL below would never appear.
  ros::NodeHandle keep_started;
  const std::string node = ros::this_node::getName();
  try {
    body();
    return 0;
  } catch (const ConfigError& error) {
    waitForRosout(ros::WallDuration(10.0));
    ROS_FATAL("%s: configuration error: %s. The node waits, doing nothing, until it is shut down: fix the "
              "configuration and start it again.", node.c_str(), error.what());
    waitWithTheError(error);
    return 0;
  } catch (const std::exception& error) {
    ROS_FATAL("%s: %s", node.c_str(), error.what());
    return kExitRuntimeFailure;
  }
}

}  // namespace docking_settings
