// A node's required parameter, read at start-up: a missing one throws std::invalid_argument naming its
// resolved name, which the node reports before it stops. One copy for the nodes that load their YAML this
// way (the arbiter, the markers). A template over the node handle, so that docking_msgs needs no roscpp
// (as estimate_check_msg.h needs no nav_msgs).
#pragma once

#include <stdexcept>
#include <string>

namespace docking_msgs {

template <typename T, typename NodeHandle>
T requireParam(const NodeHandle& nh, const std::string& name) {
  T value;
  if (!nh.getParam(name, value)) {
    throw std::invalid_argument("missing parameter '" + nh.resolveName(name) + "'");
  }
  return value;
}

}  // namespace docking_msgs
