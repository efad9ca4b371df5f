// perception_host: the whole perception pipeline in one process. A nodelet manager (same ROS API:
// load_nodelet / unload_nodelet / list services, ~num_worker_threads) that at start loads the nodelets of
// its ~nodelets list (docking_perception/host/nodelet_list.h) itself, instead of one `nodelet load`
// process per nodelet. Those loaders cost ~15 MB each and a bond each, and added nothing in-process
// loading does not do: each nodelet gets its name, parameters and remappings exactly as a loader
// would give them.
//
// A nodelet that refuses to start (its onInit throws on a bad parameter; its own FATAL says why) is
// reported and left out; the others run, and the arbiter reports the missing source silent. With none
// loaded, or with a bad list, it is a configuration error: reported once, and the host waits with it
// (docking_settings/run_node.h) instead of being respawned into the same error.
#include <docking_settings/param_reader.h>
#include <docking_settings/run_node.h>
#include <nodelet/loader.h>
#include <opencv2/core/utility.hpp>
#include <ros/ros.h>

#include <string>
#include <vector>

#include "docking_perception/host/nodelet_list.h"

namespace {

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

void runHost() {
  ros::NodeHandle private_nh("~");
  const docking_settings::ParamReader params(private_nh);
  std::vector<docking_perception::host::NodeletSpec> specs;
  std::string error;
  XmlRpc::XmlRpcValue list = params.require<XmlRpc::XmlRpcValue>("nodelets");
  docking_perception::host::parseNodeletList(list, &specs, &error);
  if (!error.empty()) params.invalid("nodelets", error);
  // OpenCV's own worker threads (block matching, remap) beside the nodelet workers: on a 2-core computer
  // they mostly wait and yield (measured: a sixth of this process's CPU in the scheduler). 1: each call
  // runs in the nodelet's thread; the nodelets still run in parallel on the worker threads.
  const int opencv_threads = params.optional<int>("opencv_threads", kOpenCvDefaultThreads);
  if (opencv_threads < kOpenCvDefaultThreads) {
    params.invalid("opencv_threads", "must be -1 (OpenCV's default), 0 or 1 (no extra threads) or a thread count");
  }
  cv::setNumThreads(opencv_threads);
  nodelet::Loader loader(true);  // the manager's ROS API and worker threads, as `nodelet manager` has
  const int loaded = loadAll(&loader, specs);
  if (loaded == 0) params.invalid("nodelets", "none of the " + std::to_string(specs.size()) + " nodelets started");
  ROS_INFO("perception_host: %d of %zu nodelets running in this process", loaded, specs.size());
  ros::spin();
}

}  // namespace

int main(int argc, char** argv) {
  ros::init(argc, argv, "perception_host");
  return docking_settings::runNode(runHost);
}
