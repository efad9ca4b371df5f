// mono_pose: the MonoPoseNodelet in its own process (same topics and parameters).
#include <nodelet/loader.h>
#include <ros/ros.h>

int main(int argc, char** argv) {
  ros::init(argc, argv, "mono_pose");
  nodelet::Loader loader(false);  // no load/unload services: this process runs one nodelet
  const nodelet::M_string remappings(ros::names::getRemappings());
  const nodelet::V_string nodelet_argv(argv + 1, argv + argc);
  if (!loader.load(ros::this_node::getName(), "docking_perception/MonoPoseNodelet", remappings, nodelet_argv)) {
    ROS_FATAL("mono_pose: could not load docking_perception/MonoPoseNodelet");
    return 1;
  }
  ros::spin();
  return 0;
}
