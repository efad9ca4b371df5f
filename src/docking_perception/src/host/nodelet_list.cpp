#include "docking_perception/host/nodelet_list.h"

#include <cctype>

namespace docking_perception {
namespace host {
namespace {

// A graph resource base name (ROS's rule): a letter, then letters, digits and underscores.
bool isBaseName(const std::string& name) {
  if (name.empty() || !std::isalpha(static_cast<unsigned char>(name[0]))) return false;
  for (const char c : name) {
    if (!std::isalnum(static_cast<unsigned char>(c)) && c != '_') return false;
  }
  return true;
}

bool isPluginType(const std::string& type) {
  const size_t slash = type.find('/');
  return slash != std::string::npos && slash > 0 && slash + 1 < type.size() && type.find('/', slash + 1) == std::string::npos;
}

// One remapping, "from:=to" as on a command line (a parameter map cannot hold it: the '/' of a topic
// name in a key would open a parameter namespace).
bool parseRemapping(XmlRpc::XmlRpcValue& item, NodeletSpec* spec, std::string* error) {
  const std::string text = item.getType() == XmlRpc::XmlRpcValue::TypeString ? static_cast<std::string>(item) : "";
  const size_t separator = text.find(":=");
  if (separator == std::string::npos || separator == 0 || separator + 2 >= text.size()) {
    *error = spec->name + ": remap entry '" + text + "' must be from:=to";
    return false;
  }
  spec->remappings[text.substr(0, separator)] = text.substr(separator + 2);
  return true;
}

bool parseRemappings(XmlRpc::XmlRpcValue& remap, NodeletSpec* spec, std::string* error) {
  if (remap.getType() != XmlRpc::XmlRpcValue::TypeArray) {
    *error = spec->name + ": remap must be a list of from:=to";
    return false;
  }
  for (int i = 0; i < remap.size(); ++i) {
    if (!parseRemapping(remap[i], spec, error)) return false;
  }
  return true;
}

bool parseEntry(const std::string& name, XmlRpc::XmlRpcValue& entry, NodeletSpec* spec, std::string* error) {
  spec->name = name;
  if (!isBaseName(name)) {
    *error = "nodelet name '" + name + "' must be a base name (letters, digits, underscores; no namespace)";
    return false;
  }
  if (entry.getType() != XmlRpc::XmlRpcValue::TypeStruct || !entry.hasMember("type") ||
      entry["type"].getType() != XmlRpc::XmlRpcValue::TypeString) {
    *error = name + ": needs type: package/Class";
    return false;
  }
  spec->type = static_cast<std::string>(entry["type"]);
  if (!isPluginType(spec->type)) {
    *error = name + ": type '" + spec->type + "' is not package/Class";
    return false;
  }
  for (auto& field : entry) {
    if (field.first != "type" && field.first != "remap") {
      *error = name + ": unknown field '" + field.first + "' (type, remap)";
      return false;
    }
  }
  return !entry.hasMember("remap") || parseRemappings(entry["remap"], spec, error);
}

}  // namespace

bool parseNodeletList(XmlRpc::XmlRpcValue& list, std::vector<NodeletSpec>* specs, std::string* error) {
  specs->clear();
  if (list.getType() != XmlRpc::XmlRpcValue::TypeStruct || list.size() == 0) {
    *error = "nodelets must be a non-empty map of name: {type, remap}";
    return false;
  }
  for (auto& entry : list) {
    NodeletSpec spec;
    if (!parseEntry(entry.first, entry.second, &spec, error)) return false;
    specs->push_back(spec);
  }
  return true;
}

}  // namespace host
}  // namespace docking_perception
