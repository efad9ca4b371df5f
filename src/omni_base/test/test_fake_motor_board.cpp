#include <gtest/gtest.h>

#include <cmath>

#include "omni_base/encoder_tracker.h"
#include "omni_base/fake_motor_board.h"

using namespace omni_base;

namespace {

FakeMotorBoardConfig boardConfig() {
  FakeMotorBoardConfig c;
  c.wheel_count = 3;
  c.drive.volts_per_rad_s = 0.5;
  c.drive.supply_volts = 12.0;
  c.motor_time_constant_s = 0.02;
  c.counts_per_rev = 1000.0;
  return c;
}

std::vector<uint8_t> dutyBytes(uint8_t seq, double rad_s, const MotorDriveModel& drive) {
  const auto d = static_cast<int16_t>(std::lround(drive.dutyFromSpeed(rad_s) * protocol::kDutyFullScale));
  return protocol::encodeFrame(protocol::makeDutyFrame({seq, {d, d, d}}));
}

}  // namespace

TEST(FakeMotorBoard, ReachesTheSetPointThroughTheMotorLagAndCountsTicks) {
  const auto cfg = boardConfig();
  FakeMotorBoard board(cfg);
  auto enable = protocol::encodeFrame(protocol::makeEnableFrame({1, true}));
  EXPECT_FALSE(board.receive(enable.data(), enable.size(), 0.0).empty());
  protocol::StreamDecoder host;
  std::vector<int32_t> last_counts;
  for (int i = 0; i <= 100; ++i) {  // 1 s at 100 Hz, 10 rad/s commanded
    const double t = i * 0.01;
    const auto cmd = dutyBytes(static_cast<uint8_t>(i), 10.0, cfg.drive);
    board.advanceTo(t);
    const auto reply = board.receive(cmd.data(), cmd.size(), t);
    const auto frames = host.feed(reply.data(), reply.size());
    ASSERT_EQ(frames.size(), 1u);
    last_counts = protocol::parseStateFrame(frames[0])->encoder_counts;
    if (i == 1) {
      EXPECT_LT(board.wheelSpeeds()[0], 10.0);  // still rising: the motor lags
    }
  }
  EXPECT_NEAR(board.wheelSpeeds()[0], 10.0, 0.01);
  // 1 s at ~10 rad/s minus the lag (tau * 10 rad = 0.2 rad) = ~9.8 rad = ~1560 counts.
  const double expected_counts = (10.0 * 1.0 - 10.0 * 0.02) / (2.0 * M_PI) * 1000.0;
  EXPECT_NEAR(last_counts[0], expected_counts, 20.0);
}

TEST(FakeMotorBoard, WatchdogStopsTheMotorsWhenCommandsStop) {
  const auto cfg = boardConfig();
  FakeMotorBoard board(cfg);
  auto enable = protocol::encodeFrame(protocol::makeEnableFrame({1, true}));
  board.receive(enable.data(), enable.size(), 0.0);
  const auto cmd = dutyBytes(2, 10.0, cfg.drive);
  board.receive(cmd.data(), cmd.size(), 0.0);
  for (double t = 0.0; t < 0.2; t += 0.001) board.advanceTo(t);
  EXPECT_GT(board.wheelSpeeds()[0], 9.0);
  for (double t = 0.2; t < 0.5; t += 0.001) board.advanceTo(t);
  EXPECT_TRUE(board.watchdogStopped());
  EXPECT_LT(std::abs(board.wheelSpeeds()[0]), 0.1);
}

TEST(FakeMotorBoard, DisabledBoardDoesNotDrive) {
  const auto cfg = boardConfig();
  FakeMotorBoard board(cfg);
  const auto cmd = dutyBytes(2, 10.0, cfg.drive);
  for (double t = 0.0; t < 0.2; t += 0.01) {
    board.receive(cmd.data(), cmd.size(), t);
    board.advanceTo(t);
  }
  EXPECT_FALSE(board.enabled());
  EXPECT_EQ(board.wheelSpeeds()[0], 0.0);
}

TEST(FakeMotorBoard, GarbageModeStillLetsTheHostDecodeEveryReply) {
  const auto cfg = boardConfig();
  FakeMotorBoard board(cfg);
  board.setGarbageBetweenFrames(true);
  protocol::StreamDecoder host;
  int replies = 0;
  for (int i = 0; i < 50; ++i) {
    const auto cmd = dutyBytes(static_cast<uint8_t>(i), 1.0, cfg.drive);
    const auto reply = board.receive(cmd.data(), cmd.size(), i * 0.01);
    replies += static_cast<int>(host.feed(reply.data(), reply.size()).size());
  }
  EXPECT_EQ(replies, 50);
  EXPECT_GT(host.garbageBytes(), 0u);
}

TEST(FakeMotorBoard, DroppedRepliesAndStallAreReported) {
  const auto cfg = boardConfig();
  FakeMotorBoard board(cfg);
  board.setReplyDropProbability(1.0);
  const auto cmd = dutyBytes(1, 1.0, cfg.drive);
  EXPECT_TRUE(board.receive(cmd.data(), cmd.size(), 0.0).empty());
  board.setReplyDropProbability(0.0);
  board.setStalled(true);
  protocol::StreamDecoder host;
  const auto reply = board.receive(cmd.data(), cmd.size(), 0.01);
  const auto frames = host.feed(reply.data(), reply.size());
  ASSERT_EQ(frames.size(), 1u);
  const auto state = protocol::parseStateFrame(frames[0]);
  EXPECT_TRUE(state->status & protocol::kStatusFault);
  EXPECT_TRUE(state->faults & protocol::kFaultStall);
}
