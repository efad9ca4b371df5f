#include <gtest/gtest.h>

#include <cmath>

#include "omni_base/encoder_tracker.h"

using omni_base::EncoderTracker;
using omni_base::EncoderTrackerConfig;

namespace {
EncoderTrackerConfig config(int bits = 32) {
  EncoderTrackerConfig c;
  c.wheel_count = 3;
  c.counts_per_rev = 1000.0;
  c.counter_bits = bits;
  c.max_plausible_rad_s = 40.0;  // 40 rad/s = 6366 counts/s: 127 counts in 20 ms
  return c;
}
}  // namespace

TEST(EncoderTracker, RollOverOfA32BitCounterIsASmallStep) {
  EncoderTracker tracker(config());
  ASSERT_TRUE(tracker.update({2147483600, -2147483600, 0}, 0.02).accepted);
  const auto s = tracker.update({-2147483646, 2147483646, 10}, 0.02);  // +50, -50 across the wrap, +10
  ASSERT_TRUE(s.accepted) << s.reason;
  const double rad_per_count = 2.0 * M_PI / 1000.0;
  EXPECT_NEAR(s.delta_rad[0], 50 * rad_per_count, 1e-12);
  EXPECT_NEAR(s.delta_rad[1], -50 * rad_per_count, 1e-12);
  EXPECT_NEAR(s.delta_rad[2], 10 * rad_per_count, 1e-12);
}

TEST(EncoderTracker, RollOverOfA16BitCounter) {
  EncoderTracker tracker(config(16));
  ASSERT_TRUE(tracker.update({65530, 3, 0}, 0.02).accepted);
  const auto s = tracker.update({4, 65533, 0}, 0.02);  // +10 and -6 across the 16-bit wrap
  ASSERT_TRUE(s.accepted) << s.reason;
  EXPECT_NEAR(s.delta_rad[0], 10 * 2.0 * M_PI / 1000.0, 1e-12);
  EXPECT_NEAR(s.delta_rad[1], -6 * 2.0 * M_PI / 1000.0, 1e-12);
}

TEST(EncoderTracker, ImplausibleJumpIsRejectedAndMovesNothing) {
  EncoderTracker tracker(config());
  tracker.update({0, 0, 0}, 0.02);
  tracker.update({100, 100, 100}, 0.02);
  const auto before = tracker.positions();
  const auto s = tracker.update({100 + 5000, 200, 200}, 0.02);  // wheel 0 glitches
  EXPECT_FALSE(s.accepted);
  EXPECT_NE(s.reason.find("wheel 0"), std::string::npos) << s.reason;
  EXPECT_EQ(tracker.positions(), before);
  // A good sample afterwards is measured from the last good counts: the glitch is forgotten.
  const auto next = tracker.update({200, 200, 200}, 0.04);
  ASSERT_TRUE(next.accepted) << next.reason;
  EXPECT_NEAR(next.delta_rad[0], 100 * 2.0 * M_PI / 1000.0, 1e-12);
  EXPECT_EQ(tracker.rejectedSamples(), 1u);
}

TEST(EncoderTracker, PersistentJumpIsTakenAsANewBaseline) {
  EncoderTracker tracker(config());
  tracker.update({1000, 1000, 1000}, 0.02);
  // The board rebooted: counters restart near zero and stay there.
  EXPECT_FALSE(tracker.update({0, 0, 0}, 0.02).accepted);
  EXPECT_FALSE(tracker.update({5, 5, 5}, 0.02).accepted);
  const auto third = tracker.update({10, 10, 10}, 0.02);
  EXPECT_FALSE(third.accepted);
  EXPECT_TRUE(third.rebaselined);
  const auto after = tracker.update({20, 20, 20}, 0.02);
  ASSERT_TRUE(after.accepted);
  EXPECT_NEAR(after.delta_rad[0], 10 * 2.0 * M_PI / 1000.0, 1e-12);
  EXPECT_EQ(tracker.rebaselines(), 1u);
}

TEST(EncoderTracker, WrongWheelCountIsRejected) {
  EncoderTracker tracker(config());
  const auto s = tracker.update({1, 2}, 0.02);
  EXPECT_FALSE(s.accepted);
  EXPECT_FALSE(s.reason.empty());
}
