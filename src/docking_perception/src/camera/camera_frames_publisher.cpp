// Publishes the static transforms base_link -> each camera's optical frame from config/robot.yaml
// (~robot_config). The real robot (robot.launch) and the simulator (sim.launch) both use it, so both
// agree on where the cameras are.
#include <docking_perception/camera/camera_mounts.h>

#include <geometry_msgs/TransformStamped.h>
#include <ros/ros.h>
#include <tf2_ros/static_transform_broadcaster.h>

#include <stdexcept>
#include <vector>

int main(int argc, char** argv) {
  ros::init(argc, argv, "camera_frames_publisher");
  ros::NodeHandle private_nh("~");

  std::string robot_config;
  if (!private_nh.getParam("robot_config", robot_config) || robot_config.empty()) {
    ROS_FATAL("missing parameter %s (path of config/robot.yaml): not starting",
              private_nh.resolveName("robot_config").c_str());
    return 1;
  }
  docking_perception::camera::RobotCameras robot;
  try {
    robot = docking_perception::camera::loadRobotCameras(robot_config);
  } catch (const std::exception& e) {
    ROS_FATAL("%s (from parameter %s): not starting", e.what(), private_nh.resolveName("robot_config").c_str());
    return 1;
  }

  std::vector<geometry_msgs::TransformStamped> transforms;
  const ros::Time stamp = ros::Time::now();
  for (const auto& mount : robot.cameras) {
    geometry_msgs::TransformStamped transform;
    transform.header.stamp = stamp;
    transform.header.frame_id = robot.base_frame;
    transform.child_frame_id = mount.frame_id;
    transform.transform.translation.x = mount.xyz_m.x();
    transform.transform.translation.y = mount.xyz_m.y();
    transform.transform.translation.z = mount.xyz_m.z();
    const Eigen::Quaterniond rotation = docking_perception::camera::quaternionFromFixedAxisRpy(mount.rpy_rad);
    transform.transform.rotation.x = rotation.x();
    transform.transform.rotation.y = rotation.y();
    transform.transform.rotation.z = rotation.z();
    transform.transform.rotation.w = rotation.w();
    transforms.push_back(transform);
    ROS_INFO("%s -> %s: xyz [%.3f %.3f %.3f] m, rpy [%.4f %.4f %.4f] rad", robot.base_frame.c_str(),
             mount.frame_id.c_str(), mount.xyz_m.x(), mount.xyz_m.y(), mount.xyz_m.z(), mount.rpy_rad.x(),
             mount.rpy_rad.y(), mount.rpy_rad.z());
  }
  tf2_ros::StaticTransformBroadcaster broadcaster;  // latched on /tf_static
  broadcaster.sendTransform(transforms);
  ros::spin();
  return 0;
}
