#include <gtest/gtest.h>

#include <vector>

#include "docking_perception/image_guard/rate_cap.h"

using docking_perception::image_guard::RateCap;

namespace {

// How many of n frames at camera_hz (stamps from start_s) a cap of cap_hz passes.
int admittedOf(RateCap* cap, double camera_hz, int n, double start_s = 100.0) {
  int admitted = 0;
  for (int i = 0; i < n; ++i) admitted += cap->admit(start_s + i / camera_hz) ? 1 : 0;
  return admitted;
}

}  // namespace

TEST(RateCap, PassesEveryThirdFrameAt30HzAndEverySecondAt15Hz) {
  RateCap at30(10.0);
  EXPECT_EQ(admittedOf(&at30, 30.0, 300), 100);
  RateCap at15(10.0);
  EXPECT_EQ(admittedOf(&at15, 15.0, 150), 75);  // 7.5 Hz: the next frame after 90 ms is 133 ms later
  RateCap slow(10.0);
  EXPECT_EQ(admittedOf(&slow, 5.0, 50), 50);     // a camera slower than the cap loses nothing
}

// perception.launch's cap: 7.5 Hz from a 15 Hz and from a 30 Hz camera alike.
TEST(RateCap, SevenAndAHalfHertzFromFifteenAndThirty) {
  RateCap at15(7.5);
  EXPECT_EQ(admittedOf(&at15, 15.0, 150), 75);
  RateCap at30(7.5);
  EXPECT_EQ(admittedOf(&at30, 30.0, 300), 75);
}

TEST(RateCap, ZeroPassesAll) {
  RateCap cap(0.0);
  EXPECT_EQ(admittedOf(&cap, 30.0, 90), 90);
}

// The image and the camera_info of a frame get one answer, whichever comes first.
TEST(RateCap, SameStampSameAnswer) {
  RateCap cap(10.0);
  const std::vector<double> stamps = {1.0, 1.0333, 1.0667, 1.1, 1.1333};
  std::vector<bool> first, second;
  for (double s : stamps) first.push_back(cap.admit(s));
  for (double s : stamps) second.push_back(cap.admit(s));
  EXPECT_EQ(first, second);
  EXPECT_EQ(first, (std::vector<bool>{true, false, false, true, false}));
}

// A frame a little early (jitter) still passes; a clock that jumps back starts over.
TEST(RateCap, ToleratesJitterAndStartsOverWhenTimeGoesBack) {
  RateCap cap(10.0);
  EXPECT_TRUE(cap.admit(5.0));
  EXPECT_TRUE(cap.admit(5.095));  // 95 ms: within the 10 % jitter allowance
  EXPECT_FALSE(cap.admit(5.105));  // 10 ms later
  EXPECT_TRUE(cap.admit(1.0));    // the replay looped
  EXPECT_FALSE(cap.admit(1.0333));
}

// The right camera's guard lowers the cap while the arbiter is on a monocular pose near, and raises it
// again: a stamp decided before the change keeps its answer (its camera_info may come after the image).
TEST(RateCap, ANewRateAppliesFromTheNextStampOn) {
  RateCap cap(7.5);
  EXPECT_EQ(admittedOf(&cap, 15.0, 30, 100.0), 15);  // 2 s at 7.5 Hz
  EXPECT_TRUE(cap.admit(102.0));
  cap.setMaxRateHz(2.5);
  EXPECT_TRUE(cap.admit(102.0)) << "decided before the change";
  EXPECT_EQ(admittedOf(&cap, 15.0, 60, 102.0 + 1.0 / 15.0), 10);  // 4 s at 2.5 Hz: every 6th frame
  cap.setMaxRateHz(7.5);
  EXPECT_EQ(admittedOf(&cap, 15.0, 30, 106.0 + 1.0 / 15.0), 15);
}
