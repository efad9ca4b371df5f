// latency_probe: the image -> cmd_vel latency in wall time, measured from outside the stack for make demo and
// the campaign (scripts/demo/run_demo.py reads its samples). It notes the wall time it receives a camera's
// camera_info (the simulator publishes it with the image, same stamp), keyed by the stamp, and pairs it
// with the wall time of the first cmd_vel after the arbiter's estimate of that stamp (the planner runs a
// cycle on each estimate it takes); the estimate splits the sample into perception (image -> estimate)
// and planner (estimate -> cmd_vel). Only estimates the planner acts on count: not while it finishes on
// odometry or is DOCKED (DockingState.target_visible false), when it ignores them on purpose.
//
// Why C++ and a node of its own: the measurement must not wait for the CPU itself. The earlier probe ran
// in the demo's Python monitor at nice 0, behind the stack at nice -5, with one thread per subscription
// and Python's 5 ms GIL switch interval; its "estimate -> cmd_vel" read a p95 of ~12 ms for a planner
// cycle of well under 1 ms. This one runs one single-threaded queue of light callbacks and is started
// ahead of the stack (sim.launch latency_probe_nice).
#include <ros/ros.h>

#include <cstdint>
#include <cstdio>
#include <map>
#include <string>
#include <vector>

#include <docking_msgs/DockingState.h>
#include <docking_msgs/TargetEstimate.h>
#include <docking_msgs/names.h>
#include <geometry_msgs/Twist.h>
#include <sensor_msgs/CameraInfo.h>

namespace {

namespace topics = docking_msgs::topics;

class LatencyProbe {
 public:
  explicit LatencyProbe(ros::NodeHandle& nh, std::FILE* samples) : samples_(samples) {
    const ros::TransportHints low_delay = ros::TransportHints().tcpNoDelay();
    // The simulator's camera_info beside each image base (image_transport's CameraPublisher convention).
    for (const char* image_topic : {topics::kStereoLeftImageRaw, topics::kIrImageRaw}) {
      const std::string info_topic = ros::names::parentNamespace(image_topic) + "/camera_info";
      subscribers_.push_back(nh.subscribe(info_topic, 5, &LatencyProbe::onCameraInfo, this, low_delay));
    }
    subscribers_.push_back(nh.subscribe(topics::kTargetEstimate, 10, &LatencyProbe::onEstimate, this, low_delay));
    subscribers_.push_back(nh.subscribe(topics::kCmdVel, 10, &LatencyProbe::onCmdVel, this, low_delay));
    subscribers_.push_back(nh.subscribe(topics::kDockingState, 10, &LatencyProbe::onState, this, low_delay));
  }

 private:
  struct PendingEstimate {
    std::uint64_t stamp_ns;
    double received_wall_s;
    std::uint8_t source;
  };
  /// Image stamps kept: 13 s of two 15 Hz cameras, far more than any estimate lags its image.
  static constexpr std::size_t kImagesKept = 400;

  static double wallNow() { return ros::WallTime::now().toSec(); }

  void onCameraInfo(const sensor_msgs::CameraInfoConstPtr& info) {
    image_wall_s_[info->header.stamp.toNSec()] = wallNow();
    while (image_wall_s_.size() > kImagesKept) image_wall_s_.erase(image_wall_s_.begin());
  }

  void onState(const docking_msgs::DockingStateConstPtr& state) {
    planner_uses_estimates_ = state->target_visible && state->state != docking_msgs::DockingState::DOCKED;
  }

  void onEstimate(const docking_msgs::TargetEstimateConstPtr& estimate) {
    if (!estimate->valid || !planner_uses_estimates_) return;
    pending_.push_back({estimate->header.stamp.toNSec(), wallNow(), estimate->selected_source});
  }

  void onCmdVel(const geometry_msgs::TwistConstPtr& /*command*/) {
    const double now = wallNow();
    for (const PendingEstimate& estimate : pending_) {
      const auto image = image_wall_s_.find(estimate.stamp_ns);
      if (image == image_wall_s_.end()) continue;  // an image from before the probe started
      // One line a sample: total, perception, planner (s), the arbiter's selected source (TargetEstimate).
      std::fprintf(samples_, "%.6f %.6f %.6f %u\n", now - image->second, estimate.received_wall_s - image->second,
                   now - estimate.received_wall_s, static_cast<unsigned>(estimate.source));
    }
    if (!pending_.empty()) std::fflush(samples_);  // read while the run goes on
    pending_.clear();
  }

  std::FILE* samples_;
  std::vector<ros::Subscriber> subscribers_;
  std::map<std::uint64_t, double> image_wall_s_;  ///< image stamp (ns) -> wall time its camera_info arrived
  std::vector<PendingEstimate> pending_;          ///< estimates waiting for the cmd_vel acting on them
  bool planner_uses_estimates_ = false;
};

}  // namespace

int main(int argc, char** argv) {
  ros::init(argc, argv, "latency_probe");
  ros::NodeHandle nh;
  ros::NodeHandle private_nh("~");
  std::string samples_path;
  if (!private_nh.getParam("samples_file", samples_path) || samples_path.empty()) {
    ROS_FATAL("latency_probe: ~samples_file (where to write the samples) is not set");
    return 1;
  }
  std::FILE* samples = std::fopen(samples_path.c_str(), "w");
  if (samples == nullptr) {
    ROS_FATAL("latency_probe: cannot write %s", samples_path.c_str());
    return 1;
  }
  {
    LatencyProbe probe(nh, samples);
    ros::spin();
  }
  std::fclose(samples);
  return 0;
}
