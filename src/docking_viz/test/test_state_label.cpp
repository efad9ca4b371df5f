// formatStateLabel and wrapText: the label of a known state, unknown numbers, long reasons; source styles.
#include <gtest/gtest.h>

#include <cmath>
#include <set>
#include <sstream>
#include <tuple>

#include "docking_viz/palette.h"
#include "docking_viz/state_label.h"

using namespace docking_viz;

namespace {

std::vector<std::string> splitLines(const std::string& text) {
  std::vector<std::string> lines;
  std::istringstream stream(text);
  for (std::string line; std::getline(stream, line);) lines.push_back(line);
  return lines;
}

}  // namespace

TEST(StateLabel, KnownStateExactText) {
  StateSummary s;
  s.state_name = "APPROACH";
  s.reason = "straight to the safe circle";
  s.time_in_state_s = 3.21;
  s.estimate_source = static_cast<std::uint8_t>(EstimateSource::kMonoVisible);
  s.target_visible = true;
  s.range_m = 1.234;
  s.goal_distance_m = 0.5;
  s.lateral_error_m = -0.0123;
  s.axial_distance_m = 1.1;
  s.yaw_error_rad = 0.1;  // 5.73 deg
  s.command = CommandedVelocity{0.12, -0.03, 0.3};
  EXPECT_EQ(formatStateLabel(s),
            "APPROACH  3.2 s\n"
            "mono visible  range 1.23 m\n"
            "goal 0.50 m  lat -0.012 m\n"
            "axial 1.10 m  yaw +5.7 deg\n"
            "cmd +0.12 -0.03 m/s +0.30 rad/s\n"
            "straight to the safe circle");
}

TEST(StateLabel, UnknownNumbersAndNoTarget) {
  StateSummary s;
  s.state_name = "SEARCH";
  s.reason = "no target";
  s.target_visible = false;
  s.range_m = s.goal_distance_m = s.lateral_error_m = s.axial_distance_m = s.yaw_error_rad = std::nan("");
  const std::string label = formatStateLabel(s);
  EXPECT_EQ(label.find("nan"), std::string::npos) << label;
  EXPECT_NE(label.find("range -- m\ngoal -- m"), std::string::npos) << label;
  EXPECT_NE(label.find("target not seen"), std::string::npos) << label;
  EXPECT_EQ(label.find("cmd"), std::string::npos) << "no command received, none shown: " << label;
}

TEST(StateLabel, LongReasonWrappedAndCut) {
  StateSummary s;
  s.state_name = "HOLD";
  s.reason = std::string(200, 'x') + " and then many more words than three lines of the label can hold, " +
             "so that the end has to be cut off somewhere before this";
  const std::vector<std::string> lines = splitLines(formatStateLabel(s));
  ASSERT_EQ(lines.size(), 4U + kMaxReasonLines);
  for (const std::string& line : std::vector<std::string>(lines.begin() + 4, lines.end())) {
    EXPECT_LE(line.size(), kLabelLineWidth) << line;
  }
  EXPECT_EQ(lines.back().substr(lines.back().size() - 3), "...");
}

TEST(EndedStateMemory, IdleSaysHowTheLastDockingEnded) {
  EndedStateMemory memory;
  EXPECT_EQ(memory.update(true, "IDLE"), "") << "start-up: no docking has ended";
  EXPECT_EQ(memory.update(false, "SEARCH"), "");
  EXPECT_EQ(memory.update(false, "FINAL"), "");
  EXPECT_EQ(memory.update(false, "DOCKED"), "");
  EXPECT_EQ(memory.update(true, "IDLE"), "DOCKED");
  EXPECT_EQ(memory.update(true, "IDLE"), "DOCKED") << "kept for as long as the planner stays idle";
  EXPECT_EQ(memory.update(false, "SEARCH"), "") << "a new docking forgets the last end";
  EXPECT_EQ(memory.update(true, "IDLE"), "SEARCH") << "cancelled while searching";
}

TEST(StateLabel, IdleAfterADockingNamesItsEnd) {
  StateSummary s;
  s.state_name = "IDLE";
  s.ended_in = "DOCKED";
  s.reason = "docked: probe tip 3.0 mm from the port";
  EXPECT_EQ(splitLines(formatStateLabel(s)).front(), "IDLE (ended in DOCKED)  0.0 s");
}

TEST(WrapText, BreaksAtSpacesOnly) {
  EXPECT_EQ(wrapText("one two three four", 9, 5), "one two\nthree\nfour");
  EXPECT_EQ(wrapText("", 9, 5), "");
  EXPECT_EQ(wrapText("one two three four", 9, 1), "one tw...");
}

TEST(SourceStyle, OneDistinctColourPerSourceAndGreyForUnknown) {
  std::set<std::tuple<float, float, float>> colours;
  std::set<std::string> keys;
  for (int source = 0; source < kSourceCount; ++source) {
    const SourceStyle& style = sourceStyle(static_cast<std::uint8_t>(source));
    colours.insert({style.colour.r, style.colour.g, style.colour.b});
    keys.insert(style.key);
  }
  EXPECT_EQ(colours.size(), static_cast<std::size_t>(kSourceCount));
  EXPECT_EQ(keys.size(), static_cast<std::size_t>(kSourceCount));
  EXPECT_STREQ(sourceStyle(static_cast<std::uint8_t>(EstimateSource::kMonoIr)).name, "mono IR");
  EXPECT_STREQ(sourceStyle(200).name, "unknown");
}
