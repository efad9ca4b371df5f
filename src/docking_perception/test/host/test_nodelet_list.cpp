#include <gtest/gtest.h>

#include <string>
#include <vector>

#include "docking_perception/host/nodelet_list.h"

using docking_perception::host::NodeletSpec;
using docking_perception::host::parseNodeletList;

namespace {

XmlRpc::XmlRpcValue entry(const std::string& type) {
  XmlRpc::XmlRpcValue value;
  value["type"] = type;
  return value;
}

}  // namespace

TEST(NodeletList, ParsesEntriesInNameOrderWithRemappings) {
  XmlRpc::XmlRpcValue list;
  list["rectify_ir"] = entry("image_proc/rectify");
  XmlRpc::XmlRpcValue guard = entry("docking_perception/ImageGuardNodelet");
  guard["remap"][0] = std::string("image_raw:=ir/image_raw");
  guard["remap"][1] = std::string("image_raw/compressed:=ir/image_raw/compressed");
  list["image_guard_ir"] = guard;
  std::vector<NodeletSpec> specs;
  std::string error;
  ASSERT_TRUE(parseNodeletList(list, &specs, &error)) << error;
  ASSERT_EQ(specs.size(), 2u);
  EXPECT_EQ(specs[0].name, "image_guard_ir");
  EXPECT_EQ(specs[0].type, "docking_perception/ImageGuardNodelet");
  ASSERT_EQ(specs[0].remappings.size(), 2u);
  EXPECT_EQ(specs[0].remappings.at("image_raw"), "ir/image_raw");
  EXPECT_EQ(specs[0].remappings.at("image_raw/compressed"), "ir/image_raw/compressed");
  EXPECT_EQ(specs[1].name, "rectify_ir");
  EXPECT_TRUE(specs[1].remappings.empty());
}

// Each mistake is refused with a message that names the nodelet (or the list) and the field.
TEST(NodeletList, RefusesMalformedListsNamingTheProblem) {
  struct Case {
    const char* what;
    XmlRpc::XmlRpcValue list;
    const char* expected_in_error;
  };
  std::vector<Case> cases;
  cases.push_back({"not a map", XmlRpc::XmlRpcValue(3), "non-empty map"});
  XmlRpc::XmlRpcValue empty;
  empty.begin();  // an empty struct
  cases.push_back({"empty", empty, "non-empty map"});
  XmlRpc::XmlRpcValue namespaced;
  namespaced["ns/guard"] = entry("a/B");
  cases.push_back({"name with a namespace", namespaced, "base name"});
  XmlRpc::XmlRpcValue no_type;
  no_type["guard"]["remap"][0] = std::string("a:=b");
  cases.push_back({"no type", no_type, "guard: needs type"});
  XmlRpc::XmlRpcValue bad_type;
  bad_type["guard"] = entry("ImageGuardNodelet");
  cases.push_back({"type without package", bad_type, "is not package/Class"});
  XmlRpc::XmlRpcValue bad_remap;
  bad_remap["guard"] = entry("a/B");
  bad_remap["guard"]["remap"][0] = std::string("image_raw=ir/image_raw");
  cases.push_back({"remap without :=", bad_remap, "guard: remap entry 'image_raw=ir/image_raw' must be from:=to"});
  XmlRpc::XmlRpcValue remap_map;
  remap_map["guard"] = entry("a/B");
  remap_map["guard"]["remap"]["image_raw"] = std::string("ir/image_raw");
  cases.push_back({"remap as a map", remap_map, "guard: remap must be a list"});
  XmlRpc::XmlRpcValue remap_to_nothing;
  remap_to_nothing["guard"] = entry("a/B");
  remap_to_nothing["guard"]["remap"][0] = std::string("image_raw:=");
  cases.push_back({"remap to nothing", remap_to_nothing, "must be from:=to"});
  XmlRpc::XmlRpcValue unknown_field;
  unknown_field["guard"] = entry("a/B");
  unknown_field["guard"]["params"] = std::string("x");
  cases.push_back({"unknown field", unknown_field, "unknown field 'params'"});
  for (Case& c : cases) {
    std::vector<NodeletSpec> specs;
    std::string error;
    EXPECT_FALSE(parseNodeletList(c.list, &specs, &error)) << c.what;
    EXPECT_NE(error.find(c.expected_in_error), std::string::npos) << c.what << ": " << error;
  }
}
