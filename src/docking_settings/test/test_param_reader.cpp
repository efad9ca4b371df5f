// The workspace's parameter reader against a live parameter server (test/param_reader.test sets the values).
#include <gtest/gtest.h>
#include <ros/ros.h>

#include <optional>

#include "docking_settings/param_reader.h"

using docking_settings::ConfigError;
using docking_settings::ConfigProblem;
using docking_settings::ParamReader;

namespace {

/// The problem a read reports, or nothing when it succeeds.
template <typename Read>
std::optional<ConfigError> errorOf(Read read) {
  try {
    read();
  } catch (const ConfigError& e) {
    return e;
  }
  return std::nullopt;
}

}  // namespace

TEST(ParamReader, ReadsEveryTypeAndTakesAnIntegerAsANumber) {
  const ParamReader p(ros::NodeHandle("reader_test"));
  EXPECT_DOUBLE_EQ(p.require<double>("rate_hz"), 50.0);
  EXPECT_DOUBLE_EQ(p.require<double>("count"), 3.0);
  EXPECT_EQ(p.require<int>("count"), 3);
  EXPECT_TRUE(p.require<bool>("enabled"));
  EXPECT_EQ(p.require<std::string>("name"), "serial");
  EXPECT_EQ(p.require<std::string>("count"), "3");  // a device index written as a number
  EXPECT_EQ(p.require<std::vector<double>>("gains"), (std::vector<double>{1.0, 2.5, 3.0}));
  EXPECT_EQ(p.require<std::vector<std::string>>("names"), (std::vector<std::string>{"a", "b"}));
  EXPECT_DOUBLE_EQ(p.optional<double>("not_there", 7.0), 7.0);
}

// Issue 53: `safe_radius_m: abc` was reported as a missing parameter.
TEST(ParamReader, AWrongTypeIsReportedAsAWrongTypeWithTheKeyAndTheValue) {
  const ParamReader p(ros::NodeHandle("reader_test"));
  const auto e = errorOf([&] { p.require<double>("safe_radius_m"); });
  ASSERT_TRUE(e);
  EXPECT_EQ(e->problem(), ConfigProblem::kWrongType);
  EXPECT_EQ(e->key(), "/reader_test/safe_radius_m");
  EXPECT_NE(std::string(e->what()).find("the string 'abc'"), std::string::npos) << e->what();
  EXPECT_EQ(errorOf([&] { p.require<int>("rate_hz"); })->problem(), ConfigProblem::kWrongType);
  EXPECT_EQ(errorOf([&] { p.require<bool>("count"); })->problem(), ConfigProblem::kWrongType);
  EXPECT_EQ(errorOf([&] { p.require<std::vector<double>>("mixed"); })->problem(), ConfigProblem::kWrongType);
  EXPECT_EQ(errorOf([&] { p.require<double>("table"); })->problem(), ConfigProblem::kWrongType);
  // optional() does not hide a wrong type behind its fallback.
  EXPECT_EQ(errorOf([&] { p.optional<double>("safe_radius_m", 1.0); })->problem(), ConfigProblem::kWrongType);
}

TEST(ParamReader, MissingAndOutOfRangeAndWrongSizeAreNamed) {
  const ParamReader p(ros::NodeHandle("reader_test"));
  const auto missing = errorOf([&] { p.require<double>("not_there"); });
  ASSERT_TRUE(missing);
  EXPECT_EQ(missing->problem(), ConfigProblem::kMissing);
  EXPECT_EQ(missing->key(), "/reader_test/not_there");
  EXPECT_EQ(errorOf([&] { p.requireInRange<double>("rate_hz", 10.0, 40.0); })->problem(), ConfigProblem::kOutOfRange);
  EXPECT_FALSE(errorOf([&] { p.requireInRange<double>("rate_hz", 10.0, 200.0); }));
  const auto entry = errorOf([&] { p.requireListInRange("gains", 3, 0.0, 2.0); });
  ASSERT_TRUE(entry);
  EXPECT_EQ(entry->problem(), ConfigProblem::kOutOfRange);
  EXPECT_EQ(entry->key(), "/reader_test/gains[1]");
  EXPECT_EQ(errorOf([&] { p.requireListInRange("gains", 2, 0.0, 5.0); })->problem(), ConfigProblem::kWrongSize);
}

int main(int argc, char** argv) {
  testing::InitGoogleTest(&argc, argv);
  ros::init(argc, argv, "test_param_reader");
  ros::NodeHandle nh;
  return RUN_ALL_TESTS();
}
