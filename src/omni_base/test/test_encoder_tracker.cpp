#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>

#include "omni_base/encoder_tracker.h"
#include "omni_base/kinematics.h"
#include "omni_base/motor.h"
#include "omni_base/odometry.h"

using omni_base::EncoderEvent;
using omni_base::EncoderFrame;
using omni_base::EncoderTracker;
using omni_base::EncoderTrackerConfig;

namespace {

constexpr double kRadPerCount = 2.0 * M_PI / 1000.0;

EncoderTrackerConfig config(int bits = 32) {
  EncoderTrackerConfig c;
  c.wheel_count = 3;
  c.counts_per_rev = 1000.0;
  c.counter_bits = bits;
  c.max_plausible_rad_s = 40.0;  // 40 rad/s = 6366 counts/s: 127 counts in 20 ms
  return c;
}

/// A board frame latched at board time board_ms and received by the host at host_s.
EncoderFrame frame(std::vector<int32_t> counts, uint32_t board_ms, double host_s) {
  return EncoderFrame{std::move(counts), board_ms, host_s};
}

}  // namespace

TEST(EncoderTracker, RollOverOfA32BitCounterIsASmallStep) {
  EncoderTracker tracker(config());
  ASSERT_TRUE(tracker.update(frame({2147483600, -2147483600, 0}, 1000, 10.0)).accepted());
  const auto s = tracker.update(frame({-2147483646, 2147483646, 10}, 1020, 10.02));  // +50, -50 across the wrap
  ASSERT_EQ(s.event, EncoderEvent::kAccepted) << s.reason;
  EXPECT_NEAR(s.delta_rad[0], 50 * kRadPerCount, 1e-12);
  EXPECT_NEAR(s.delta_rad[1], -50 * kRadPerCount, 1e-12);
  EXPECT_NEAR(s.delta_rad[2], 10 * kRadPerCount, 1e-12);
  EXPECT_NEAR(s.dt_s, 0.02, 1e-12);
}

TEST(EncoderTracker, WheelVelocitiesAreTheSampleDeltaOverItsBoardTime) {
  EncoderTracker tracker(config());
  const auto baseline = tracker.update(frame({0, 0, 0}, 1000, 10.0));
  EXPECT_EQ(baseline.wheelVelocities(), std::vector<double>(3, 0.0));  // dt 0: no velocity yet
  const auto s = tracker.update(frame({40, -20, 0}, 1020, 10.5));        // board time 20 ms, host time ignored
  ASSERT_EQ(s.event, EncoderEvent::kAccepted) << s.reason;
  const std::vector<double> v = s.wheelVelocities();
  EXPECT_NEAR(v[0], 40 * kRadPerCount / 0.02, 1e-9);
  EXPECT_NEAR(v[1], -20 * kRadPerCount / 0.02, 1e-9);
  EXPECT_NEAR(v[2], 0.0, 1e-12);
}

TEST(EncoderTracker, RollOverOfA16BitCounter) {
  EncoderTracker tracker(config(16));
  ASSERT_TRUE(tracker.update(frame({65530, 3, 0}, 1000, 10.0)).accepted());
  const auto s = tracker.update(frame({4, 65533, 0}, 1020, 10.02));  // +10 and -6 across the 16-bit wrap
  ASSERT_EQ(s.event, EncoderEvent::kAccepted) << s.reason;
  EXPECT_NEAR(s.delta_rad[0], 10 * kRadPerCount, 1e-12);
  EXPECT_NEAR(s.delta_rad[1], -6 * kRadPerCount, 1e-12);
}

TEST(EncoderTracker, BoardClockRollOverIsASmallStep) {
  EncoderTracker tracker(config());
  ASSERT_TRUE(tracker.update(frame({0, 0, 0}, 0xFFFFFFF0u, 10.0)).accepted());
  const auto s = tracker.update(frame({100, 0, 0}, 0x00000004u, 10.02));  // 20 ms across the wrap
  ASSERT_EQ(s.event, EncoderEvent::kAccepted) << s.reason;
  EXPECT_NEAR(s.dt_s, 0.020, 1e-12);
}

TEST(EncoderTracker, ImplausibleJumpIsRejectedAndMovesNothing) {
  EncoderTracker tracker(config());
  tracker.update(frame({0, 0, 0}, 1000, 10.0));
  tracker.update(frame({100, 100, 100}, 1020, 10.02));
  const auto before = tracker.positions();
  const auto s = tracker.update(frame({100 + 5000, 200, 200}, 1040, 10.04));  // wheel 0 glitches
  EXPECT_EQ(s.event, EncoderEvent::kImplausibleJump);
  EXPECT_FALSE(s.accepted());
  EXPECT_EQ(tracker.positions(), before);
  // A good sample afterwards is measured from the last good counts and board time: nothing is lost.
  const auto next = tracker.update(frame({200, 200, 200}, 1060, 10.06));
  ASSERT_EQ(next.event, EncoderEvent::kAccepted) << next.reason;
  EXPECT_NEAR(next.delta_rad[0], 100 * kRadPerCount, 1e-12);
  EXPECT_NEAR(next.dt_s, 0.040, 1e-12);
  EXPECT_EQ(tracker.rejectedSamples(), 1u);
}

// Issue 12: the node stalls 120 ms, then five frames (board clock 20 ms apart) arrive at one host time.
// The plausibility check must use the board time since the last accepted sample, and count every tick.
TEST(EncoderTracker, BurstAfterAStallCountsEveryTickExactly) {
  EncoderTracker tracker(config());
  ASSERT_TRUE(tracker.update(frame({0, 0, 0}, 5000, 100.0)).accepted());
  const int32_t counts_per_frame = 120;  // 37.7 rad/s: near the plausible limit
  const double burst_host_s = 100.0 + 0.120;
  for (int k = 1; k <= 5; ++k) {
    const auto s = tracker.update(
        frame({k * counts_per_frame, -k * counts_per_frame, k * 7}, static_cast<uint32_t>(5000 + 20 * k), burst_host_s));
    ASSERT_EQ(s.event, EncoderEvent::kAccepted) << "frame " << k << ": " << s.reason;
    EXPECT_NEAR(s.dt_s, 0.020, 1e-12);
  }
  EXPECT_DOUBLE_EQ(tracker.positions()[0], 5 * counts_per_frame * kRadPerCount);
  EXPECT_DOUBLE_EQ(tracker.positions()[1], -5 * counts_per_frame * kRadPerCount);
  EXPECT_DOUBLE_EQ(tracker.positions()[2], 5 * 7 * kRadPerCount);
  EXPECT_EQ(tracker.rejectedSamples(), 0u);
}

// Issue 12: driving at 0.3 m/s for 60 s while the host stalls 120 ms every 400 ms (frames then arrive
// in bursts): odometry must match the distance the board's counters say within 0.1 %.
TEST(EncoderTracker, OdometryUnderAStallPatternMatchesTheBoard) {
  omni_base::WheelLayout layout{{0.0, 2.0 * M_PI / 3.0, 4.0 * M_PI / 3.0}, 0.10, 0.024};
  const omni_base::OmniKinematics kinematics(layout);
  EncoderTrackerConfig cfg = config();
  cfg.counts_per_rev = 1320.0;
  cfg.max_plausible_rad_s = 2.0 * 12.0 / 0.55;
  EncoderTracker tracker(cfg);
  omni_base::OdometryIntegrator odometry;

  const auto wheel_rad_s = kinematics.inverse({0.3, 0.0, 0.0});
  const double board_clock_offset_s = 1234.5;  // the board clock is not the host clock
  const double latency_s = 0.002;
  const int frames = 3000;                     // 60 s at 50 Hz
  int next_frame = 0;
  std::vector<int32_t> last_counts;
  for (int cycle = 0; next_frame < frames; ++cycle) {
    const double host_s = 0.007 + 0.02 * cycle;
    const double phase = std::fmod(host_s, 0.4);
    if (phase >= 0.1 && phase < 0.22) continue;  // stalled: the frames wait in the serial buffer
    for (; next_frame < frames && next_frame * 0.02 + latency_s <= host_s; ++next_frame) {
      const double t = next_frame * 0.02;
      last_counts.clear();
      for (double w : wheel_rad_s) last_counts.push_back(omni_base::encoderCountsFromAngle(w * t, 1320.0));
      const auto board_ms = static_cast<uint32_t>(std::llround((t + board_clock_offset_s) * 1000.0));
      const auto s = tracker.update(frame(last_counts, board_ms, host_s));
      ASSERT_TRUE(s.accepted()) << "frame " << next_frame << ": " << s.reason;
      odometry.integrateDisplacement(kinematics.forward(s.delta_rad));
    }
  }
  std::vector<double> board_angles;
  for (int32_t c : last_counts) board_angles.push_back(c * 2.0 * M_PI / 1320.0);
  const double board_distance = kinematics.forward(board_angles).vx;
  const double odom_distance = std::hypot(odometry.pose().x, odometry.pose().y);
  std::printf("measured: stall pattern, odometry %.9f m, board %.9f m, error %.3g %%\n", odom_distance,
              board_distance, 100.0 * std::abs(odom_distance - board_distance) / board_distance);
  EXPECT_NEAR(board_distance, 0.3 * 59.98, 0.3 * 59.98 * 1e-3);
  EXPECT_LE(std::abs(odom_distance - board_distance), 1e-3 * board_distance)
      << "odometry " << odom_distance << " m, board " << board_distance << " m";
  EXPECT_EQ(tracker.rejectedSamples(), 0u);
}

/// Feeds frames that continue a restarted clock (board and host 20 ms apart, `step` counts each) until
/// the tracker confirms the reboot or `frames` have gone in; returns the last sample.
EncoderTracker::Sample continueNewClock(EncoderTracker& tracker, std::vector<int32_t> counts, uint32_t board_ms,
                                        double host_s, int32_t step, int frames) {
  EncoderTracker::Sample s;
  for (int k = 0; k < frames; ++k) {
    for (auto& c : counts) c += step;
    board_ms += 20;
    host_s += 0.02;
    s = tracker.update(frame(counts, board_ms, host_s));
    if (s.event != EncoderEvent::kRebootPending) break;
  }
  return s;
}

// A fast reboot: the board clock restarts and the counters restart near zero. /odom must not jump by
// the old counter values; nothing moves until the frames that follow continue the new clock, then the
// counts since boot are counted, none lost.
TEST(EncoderTracker, RebootIsConfirmedByTheFramesThatFollowAndDoesNotJump) {
  EncoderTracker tracker(config());
  tracker.update(frame({0, 0, 0}, 600000, 50.0));
  ASSERT_EQ(tracker.update(frame({50000, -30000, 12000}, 620000, 70.0)).event, EncoderEvent::kAccepted);
  const auto before = tracker.positions();
  const auto claim = tracker.update(frame({2, -1, 0}, 150, 70.2));  // rebooted 150 ms ago, barely moved since
  EXPECT_EQ(claim.event, EncoderEvent::kRebootPending) << claim.reason;
  EXPECT_EQ(tracker.positions(), before);
  const int more = EncoderTracker::kRebootConfirmationFrames;
  const auto confirmed = continueNewClock(tracker, {2, -1, 0}, 150, 70.2, 3, more);
  EXPECT_EQ(confirmed.event, EncoderEvent::kBoardRebooted) << confirmed.reason;
  EXPECT_NEAR(tracker.positions()[0] - before[0], (2 + 3 * more) * kRadPerCount, 1e-12);  // since boot
  EXPECT_NEAR(tracker.positions()[1] - before[1], (-1 + 3 * more) * kRadPerCount, 1e-12);
  EXPECT_EQ(tracker.reboots(), 1u);
  EXPECT_EQ(tracker.refusedReboots(), 0u);
  // It carries on from the new clock and counters.
  const auto next = tracker.update(frame({12 + 3 * more, 9, 10}, 170 + 20 * more, 70.22 + 0.02 * more));
  ASSERT_EQ(next.event, EncoderEvent::kAccepted) << next.reason;
  EXPECT_NEAR(next.delta_rad[0], 10 * kRadPerCount, 1e-12);
}

// A reboot during a disconnect longer than the board had been up: the clock ends up ahead, but the
// board's uptime is shorter than the silence, so it is still a reboot.
TEST(EncoderTracker, RebootDuringALongSilenceIsDetected) {
  EncoderTracker tracker(config());
  tracker.update(frame({0, 0, 0}, 1000, 10.0));
  tracker.update(frame({3000, 3000, 3000}, 2000, 11.0));
  EXPECT_EQ(tracker.update(frame({1, 0, 0}, 4000, 20.0)).event, EncoderEvent::kRebootPending);  // 9 s silence, up 4 s
  const auto s = continueNewClock(tracker, {1, 0, 0}, 4000, 20.0, 0, EncoderTracker::kRebootConfirmationFrames);
  EXPECT_EQ(s.event, EncoderEvent::kBoardRebooted) << s.reason;
  EXPECT_NEAR(tracker.positions()[0], (3000 + 1) * kRadPerCount, 1e-12);
}

/// The issue-53 base: 1320 counts per revolution, plausible up to twice 12 V / 0.55 V per rad/s.
EncoderTrackerConfig shippedConfig() {
  EncoderTrackerConfig c = config();
  c.counts_per_rev = 1320.0;
  c.max_plausible_rad_s = 2.0 * 12.0 / 0.55;
  return c;
}

/// Drives the board's true counters at `counts_per_frame` per 20 ms from `board_ms` for `frames` frames;
/// returns the host time of the last one.
double driveOldTimeline(EncoderTracker& tracker, std::vector<int32_t>& counts, uint32_t& board_ms, double host_s,
                        int32_t counts_per_frame, int frames) {
  for (int k = 0; k < frames; ++k) {
    counts[0] += counts_per_frame;
    counts[1] -= counts_per_frame / 2;
    counts[2] -= counts_per_frame / 2;
    board_ms += 20;
    host_s += 0.02;
    const auto s = tracker.update(frame(counts, board_ms, host_s));
    EXPECT_TRUE(s.event == EncoderEvent::kAccepted || s.event == EncoderEvent::kRebootRefuted) << s.reason;
  }
  return host_s;
}

// Issue 53: one CRC-valid frame that looks like a reboot 2 s ago (counts under the since-boot limit) sent
// 20 ms after a normal frame moved /odom by 2 m. The board answered 20 ms ago: it cannot have been up for
// 2 s. The frame is refused and the old timeline carries on, every count of it kept.
TEST(EncoderTracker, OneFakeRebootFrameMovesNothing) {
  EncoderTracker tracker(shippedConfig());
  std::vector<int32_t> counts{40000, -20000, -20000};
  uint32_t board_ms = 60000;
  tracker.update(frame(counts, board_ms, 100.0));
  double host_s = driveOldTimeline(tracker, counts, board_ms, 100.0, 60, 20);
  const auto before = tracker.positions();
  const auto fake = tracker.update(frame({18000, -9000, -9000}, 2000, host_s + 0.005));
  EXPECT_EQ(fake.event, EncoderEvent::kRebootImplausible) << fake.reason;
  EXPECT_FALSE(fake.accepted());
  EXPECT_EQ(tracker.positions(), before);
  driveOldTimeline(tracker, counts, board_ms, host_s, 60, 50);
  EXPECT_NEAR(tracker.positions()[0], 70 * 60 * 2.0 * M_PI / 1320.0, 1e-9);  // every true count, no more
  EXPECT_EQ(tracker.reboots(), 0u);
  EXPECT_EQ(tracker.refusedReboots(), 1u);
  EXPECT_EQ(tracker.rebaselines(), 0u);
}

// Issue 53: a reboot claim that fits the host's silence (up 10 ms, a few counts), then the old timeline
// goes on: the claim is held, nothing counted, and the first old-timeline frame refutes it.
TEST(EncoderTracker, AHeldRebootClaimIsRefutedByTheOldTimeline) {
  EncoderTracker tracker(shippedConfig());
  std::vector<int32_t> counts{40000, -20000, -20000};
  uint32_t board_ms = 60000;
  tracker.update(frame(counts, board_ms, 100.0));
  double host_s = driveOldTimeline(tracker, counts, board_ms, 100.0, 60, 20);
  const auto claim = tracker.update(frame({5, 0, 0}, 10, host_s + 0.01));
  EXPECT_EQ(claim.event, EncoderEvent::kRebootPending) << claim.reason;
  counts[0] += 60;
  counts[1] -= 30;
  counts[2] -= 30;
  board_ms += 20;
  const auto refuted = tracker.update(frame(counts, board_ms, host_s + 0.02));
  EXPECT_EQ(refuted.event, EncoderEvent::kRebootRefuted) << refuted.reason;
  EXPECT_TRUE(refuted.accepted());
  driveOldTimeline(tracker, counts, board_ms, host_s + 0.02, 60, 30);
  EXPECT_NEAR(tracker.positions()[0], 51 * 60 * 2.0 * M_PI / 1320.0, 1e-9);
  EXPECT_EQ(tracker.reboots(), 0u);
  EXPECT_EQ(tracker.refusedReboots(), 1u);
}

// A claim that fits the silence but whose following frames continue neither clock: held, never counted.
TEST(EncoderTracker, AClaimWithoutAConsistentClockIsNeverConfirmed) {
  EncoderTracker tracker(shippedConfig());
  tracker.update(frame({40000, 0, 0}, 60000, 100.0));
  tracker.update(frame({40060, 0, 0}, 60020, 100.02));
  EXPECT_EQ(tracker.update(frame({5, 0, 0}, 10, 100.04)).event, EncoderEvent::kRebootPending);
  // The "new clock" leaps 5 s in 20 ms of host time: not a clock.
  const auto leap = tracker.update(frame({6, 0, 0}, 5010, 100.06));
  EXPECT_FALSE(leap.accepted()) << leap.reason;
  EXPECT_EQ(tracker.reboots(), 0u);
  EXPECT_EQ(tracker.positions()[0], 60 * 2.0 * M_PI / 1320.0);
}

// Issue 12: one valid frame with the board clock 2^31 ms ahead moved /odom 22.8 m.
TEST(EncoderTracker, ClockJumpMovesNothingAndLosesNothing) {
  EncoderTracker tracker(config());
  tracker.update(frame({0, 0, 0}, 1000, 10.0));
  tracker.update(frame({20, 20, 20}, 1020, 10.02));
  const auto before = tracker.positions();
  // 2^31 ms ahead of the frame's true time reads as "back" by 2^31 - 20 ms; 2^30 ms reads as ahead.
  for (uint32_t jump : {0x80000000u, 0x40000000u}) {
    const auto jumped = tracker.update(frame({1000000, 40, 40}, 1040u + jump, 10.04));
    EXPECT_FALSE(jumped.accepted()) << jumped.reason;
    EXPECT_EQ(jumped.event, EncoderEvent::kClockJumped);
    EXPECT_EQ(tracker.positions(), before);
  }
  const auto next = tracker.update(frame({60, 60, 60}, 1060, 10.06));
  ASSERT_EQ(next.event, EncoderEvent::kAccepted) << next.reason;
  EXPECT_NEAR(tracker.positions()[0], 60 * kRadPerCount, 1e-12);
  EXPECT_EQ(tracker.reboots(), 0u);
}

TEST(EncoderTracker, ClockGoingBackWithoutAFreshBootIsRejected) {
  EncoderTracker tracker(config());
  tracker.update(frame({50000, 0, 0}, 600000, 10.0));
  const auto s = tracker.update(frame({50010, 0, 0}, 100, 10.02));  // the counters did not restart
  EXPECT_EQ(s.event, EncoderEvent::kRebootImplausible) << s.reason;
  EXPECT_EQ(tracker.reboots(), 0u);
  EXPECT_EQ(tracker.positions()[0], 0.0);
}

TEST(EncoderTracker, PersistentJumpIsTakenAsANewBaseline) {
  EncoderTracker tracker(config());
  tracker.update(frame({1000, 1000, 1000}, 5000, 10.0));
  // The counters jumped (not a reboot: the clock runs on) and stay there.
  EXPECT_EQ(tracker.update(frame({90000, 1000, 1000}, 5020, 10.02)).event, EncoderEvent::kImplausibleJump);
  EXPECT_EQ(tracker.update(frame({90005, 1000, 1000}, 5040, 10.04)).event, EncoderEvent::kImplausibleJump);
  const auto third = tracker.update(frame({90010, 1000, 1000}, 5060, 10.06));
  EXPECT_EQ(third.event, EncoderEvent::kRebaselined);
  EXPECT_EQ(tracker.positions()[0], 0.0);  // an implausible jump is never counted
  const auto after = tracker.update(frame({90020, 1000, 1000}, 5080, 10.08));
  ASSERT_EQ(after.event, EncoderEvent::kAccepted) << after.reason;
  EXPECT_NEAR(after.delta_rad[0], 10 * kRadPerCount, 1e-12);
  EXPECT_EQ(tracker.rebaselines(), 1u);
}

TEST(EncoderTracker, WrongWheelCountIsRejected) {
  EncoderTracker tracker(config());
  const auto s = tracker.update(frame({1, 2}, 0, 0.0));
  EXPECT_EQ(s.event, EncoderEvent::kWrongWheelCount);
  EXPECT_FALSE(s.reason.empty());
}
