// disparity_detector: the DisparityDetectorNodelet in its own process (same topics and parameters).
#include <nodelet/loader.h>
#include <ros/ros.h>

int main(int argc, char** argv) {
  ros::init(argc, argv, "disparity_detector");
  nodelet::Loader loader(false);  // no load/unload services: this process runs one nodelet
  const nodelet::M_string remappings(ros::names::getRemappings());
  const nodelet::V_string nodelet_argv(argv + 1, argv + argc);
  if (!loader.load(ros::this_node::getName(), "docking_perception/DisparityDetectorNodelet",
                   remappings, nodelet_argv)) {
    ROS_FATAL("disparity_detector: could not load docking_perception/DisparityDetectorNodelet");
    return 1;
  }
  ros::spin();
  return 0;
}
