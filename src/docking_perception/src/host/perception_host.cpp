// perception_host: the whole perception pipeline in one process. A nodelet manager (same ROS API:
// load_nodelet / unload_nodelet / list services, ~num_worker_threads) that at start loads the nodelets of
// its ~nodelets list (docking_perception/host/nodelet_list.h) itself, instead of one `nodelet load`
// process per nodelet. Those loaders cost ~15 MB each and a bond each, and added nothing in-process
// loading does not do: each nodelet gets its name, parameters and remappings exactly as a loader
// would give them.
//
// A nodelet that refuses to start (its onInit throws on a bad parameter; its own FATAL says why) is
// reported and left out; the others run, and the arbiter reports the missing source silent. With none
// loaded the host exits non-zero (roslaunch respawns it).
#include <nodelet/loader.h>
#include <opencv2/core/utility.hpp>
#include <ros/ros.h>

#include <string>
#include <vector>

#include "docking_perception/host/nodelet_list.h"

namespace {

constexpr int kExitNothingLoaded = 1;
constexpr int kExitBadList = 2;
constexpr int kExitBadParameter = 3;
constexpr int kOpenCvDefaultThreads = -1;  // cv::setNumThreads(-1): OpenCV's own default (all cores)

// Remappings as `nodelet load` passes them: both sides resolved in the host's namespace.
nodelet::M_string resolvedRemappings(const docking_perception::host::NodeletSpec& spec) {
  nodelet::M_string resolved;
  for (const auto& remap : spec.remappings) {
    resolved[ros::names::resolve(remap.first, false)] = ros::names::resolve(remap.second, false);
  }
  return resolved;
}

int loadAll(nodelet::Loader* loader, const std::vector<docking_perception::host::NodeletSpec>& specs) {
  int loaded = 0;
  for (const auto& spec : specs) {
    const std::string name = ros::names::resolve(spec.name);
    if (loader->load(name, spec.type, resolvedRemappings(spec), nodelet::V_string())) {
      ++loaded;
    } else {
      ROS_FATAL("perception_host: nodelet %s (%s) did not start (its own error is above); running without it",
                name.c_str(), spec.type.c_str());
    }
  }
  return loaded;
}

}  // namespace

int main(int argc, char** argv) {
  ros::init(argc, argv, "perception_host");
  ros::NodeHandle private_nh("~");
  XmlRpc::XmlRpcValue list;
  std::vector<docking_perception::host::NodeletSpec> specs;
  std::string error;
  if (!private_nh.getParam("nodelets", list)) {
    error = "parameter " + private_nh.resolveName("nodelets") + " is not set";
  } else {
    docking_perception::host::parseNodeletList(list, &specs, &error);
  }
  if (!error.empty()) {
    ROS_FATAL("perception_host: %s", error.c_str());
    return kExitBadList;
  }
  // OpenCV's own worker threads (block matching, remap) beside the nodelet workers: on a 2-core computer
  // they mostly wait and yield (measured: a sixth of this process's CPU in the scheduler). 1: each call
  // runs in the nodelet's thread; the nodelets still run in parallel on the worker threads.
  int opencv_threads = kOpenCvDefaultThreads;
  private_nh.param("opencv_threads", opencv_threads, kOpenCvDefaultThreads);
  if (opencv_threads < kOpenCvDefaultThreads) {
    ROS_FATAL("perception_host: ~opencv_threads must be -1 (OpenCV's default), 0 or 1 (no extra threads) "
              "or a thread count; got %d", opencv_threads);
    return kExitBadParameter;
  }
  cv::setNumThreads(opencv_threads);
  nodelet::Loader loader(true);  // the manager's ROS API and worker threads, as `nodelet manager` has
  const int loaded = loadAll(&loader, specs);
  if (loaded == 0) {
    ROS_FATAL("perception_host: none of the %zu nodelets started", specs.size());
    return kExitNothingLoaded;
  }
  ROS_INFO("perception_host: %d of %zu nodelets running in this process", loaded, specs.size());
  ros::spin();
  return 0;
}
