#pragma once
// The perception host's list of nodelets (its ~nodelets parameter): which nodelets to load into the one
// perception process, each with its topic remappings. One process instead of a nodelet manager plus
// one `nodelet load` process per nodelet (each of those ~15 MB and a bond's CPU; docs/PERFORMANCE.md).
//
// Format (a struct keyed by nodelet name, loaded in name order):
//   nodelets:
//     mono_pose_visible:
//       type: docking_perception/MonoPoseNodelet
//       remap: [stereo/left/camera_info:=stereo/left/camera_info_checked]   (from:=to, as on a command line)
// A nodelet's own parameters sit where a loader's would: under its name in the host's namespace.

#include <map>
#include <string>
#include <vector>

#include <xmlrpcpp/XmlRpcValue.h>

namespace docking_perception {
namespace host {

struct NodeletSpec {
  std::string name;                              // base name, e.g. "mono_pose_visible"
  std::string type;                              // pluginlib name, "package/Class"
  std::map<std::string, std::string> remappings;  // from -> to, names relative to the host's namespace
};

// Parses and checks the list. False with the first problem in *error (naming the nodelet and the field)
// when the value is not a non-empty struct of {type, remap} entries, a name is not a plain base name,
// a type is not "package/Class", or a remapping is not a "from:=to" string.
bool parseNodeletList(XmlRpc::XmlRpcValue& list, std::vector<NodeletSpec>* specs, std::string* error);

}  // namespace host
}  // namespace docking_perception
