// The topic and frame names shared by every package: one place to read them, one place to change them.
// Topic names are relative, so that a launch file can push a whole robot into a namespace.
#pragma once

namespace docking_msgs {
namespace topics {
// Base
constexpr const char kCmdVel[] = "cmd_vel";                  // geometry_msgs/Twist, base_link
constexpr const char kOdom[] = "odom";                       // nav_msgs/Odometry, odom -> base_link
constexpr const char kEStop[] = "e_stop";                    // std_msgs/Bool, true latches a stop
constexpr const char kWheelCommand[] = "wheels/command";     // docking_msgs/WheelCommand
constexpr const char kWheelEncoders[] = "wheels/encoders";   // docking_msgs/WheelEncoders
constexpr const char kWheelState[] = "wheels/state";         // docking_msgs/WheelState
// sensor_msgs/JointState of the wheels for robot_state_publisher: names are the URDF's wheel joints
// (omni_base.yaml wheels/names), position the accumulated angle (rad), velocity the measured speed.
constexpr const char kJointStates[] = "joint_states";

// Cameras (image_transport bases; camera_info beside each)
constexpr const char kStereoLeftImageRaw[] = "stereo/left/image_raw";
constexpr const char kStereoRightImageRaw[] = "stereo/right/image_raw";
// image_raw that passed docking_perception's image guard (launch/perception.launch): what image_proc reads.
constexpr const char kStereoLeftImageChecked[] = "stereo/left/image_checked";
constexpr const char kStereoRightImageChecked[] = "stereo/right/image_checked";
constexpr const char kIrImageChecked[] = "ir/image_checked";
// camera_info that passed the guard (well formed, the size of the camera's last checked image): what
// image_proc's rectify, stereo_image_proc and our estimators read (launch/perception.launch remaps them).
constexpr const char kStereoLeftCameraInfoChecked[] = "stereo/left/camera_info_checked";
constexpr const char kStereoRightCameraInfoChecked[] = "stereo/right/camera_info_checked";
constexpr const char kIrCameraInfoChecked[] = "ir/camera_info_checked";
// Grey, not rectified (image_proc/debayer's image_mono in perception.launch).
constexpr const char kStereoLeftImageMono[] = "stereo/left/image_mono";
constexpr const char kStereoRightImageMono[] = "stereo/right/image_mono";
constexpr const char kStereoLeftImageRect[] = "stereo/left/image_rect";
// The far stage's own rectified pair (docking_perception/FarStereoRectifyNodelet, config/far_stereo.yaml),
// grey, at full resolution: the whole image, or a window around the tracked target (its camera_info's region
// of interest says where). Block-matched by stereo_disparity.
constexpr const char kStereoFarFullLeftImageRect[] = "stereo/far/full/left/image_rect";
constexpr const char kStereoFarFullLeftCameraInfo[] = "stereo/far/full/left/camera_info";
constexpr const char kStereoFarFullRightImageRect[] = "stereo/far/full/right/image_rect";
constexpr const char kStereoFarFullRightCameraInfo[] = "stereo/far/full/right/camera_info";
constexpr const char kStereoDisparity[] = "stereo/disparity";  // stereo_msgs/DisparityImage
constexpr const char kIrImageRaw[] = "ir/image_raw";
constexpr const char kIrImageRect[] = "ir/image_rect";

// Perception
constexpr const char kDisparityEstimate[] = "perception/disparity/estimate";        // TargetEstimate
constexpr const char kMonoVisibleEstimate[] = "perception/mono_visible/estimate";  // TargetEstimate
constexpr const char kMonoIrEstimate[] = "perception/mono_ir/estimate";            // TargetEstimate
constexpr const char kTargetEstimate[] = "target/estimate";    // TargetEstimate (FUSED)
constexpr const char kTargetPose[] = "target/pose";            // geometry_msgs/PoseWithCovarianceStamped
constexpr const char kTargetTwist[] = "target/twist";          // geometry_msgs/TwistWithCovarianceStamped
constexpr const char kArbiterStatus[] = "target/arbiter_status";  // std_msgs/String

// Planner
constexpr const char kDockingState[] = "docking/state";        // docking_msgs/DockingState
constexpr const char kDockingPath[] = "docking/path";          // nav_msgs/Path
constexpr const char kDockingGeometry[] = "docking/geometry";  // docking_msgs/PlannerGeometry (lazy)
constexpr const char kDockingMarkers[] = "docking/markers";    // visualization_msgs/MarkerArray (docking_viz, lazy)
constexpr const char kDockAction[] = "docking/dock";           // actionlib: docking_msgs/Dock (goal, cancel, feedback, result)

// Simulator ground truth: nav_msgs/Odometry of the target in each camera's optical frame, at each
// image stamp (header.frame_id = camera optical frame, child_frame_id = target).
constexpr const char kTruthStereoLeft[] = "sim/truth/stereo_left";
constexpr const char kTruthIr[] = "sim/truth/ir";
constexpr const char kTruthChaserOdom[] = "sim/truth/chaser";  // nav_msgs/Odometry, world -> chaser_truth
}  // namespace topics

namespace frames {
constexpr const char kWorld[] = "world";          // simulator only
constexpr const char kOdom[] = "odom";
constexpr const char kBaseLink[] = "base_link";
constexpr const char kStereoLeftOptical[] = "stereo_left_optical_frame";
constexpr const char kStereoRightOptical[] = "stereo_right_optical_frame";
constexpr const char kIrOptical[] = "ir_optical_frame";
constexpr const char kTarget[] = "target";        // the docking port: origin at its centre, x out of the face
constexpr const char kChaserTruth[] = "chaser_truth";  // simulator only
constexpr const char kTargetTruth[] = "target_truth";  // simulator only (the port, true pose)
}  // namespace frames

namespace diagnostics {
// The camera nodes' diagnostic task: their statuses on /diagnostics are named "<node>: camera capture" and
// say what is wrong with their source. The planner cites those that are not OK when perception is gone.
constexpr const char kCameraCapture[] = "camera capture";
}  // namespace diagnostics
}  // namespace docking_msgs
