#include <gtest/gtest.h>

#include <cmath>

#include "omni_base/board_session.h"
#include "omni_base/encoder_tracker.h"
#include "omni_base/fake_motor_board.h"
#include "omni_base/kinematics.h"
#include "omni_base/odometry.h"

using namespace omni_base;

TEST(EnableHandshake, SendsOnConnectAndOnChangeOnly) {
  EnableHandshake h;
  EXPECT_TRUE(h.shouldSend(true));
  h.sent(true, 10);
  EXPECT_FALSE(h.shouldSend(true));
  EXPECT_TRUE(h.shouldSend(false));
  h.onBoardState(10, true);
  EXPECT_TRUE(h.confirmed());
  EXPECT_FALSE(h.shouldSend(true));
}

TEST(EnableHandshake, BoardThatDropsItsEnableGetsItAgain) {
  EnableHandshake h;
  h.sent(true, 250);
  h.onBoardState(249, false);  // answers a command sent before the ENABLE: says nothing
  EXPECT_FALSE(h.shouldSend(true));
  EXPECT_FALSE(h.confirmed());
  h.onBoardState(251, true);
  EXPECT_TRUE(h.confirmed());
  h.onBoardState(3, false);    // after the sequence wrapped: the board rebooted and starts disabled
  EXPECT_FALSE(h.confirmed());
  EXPECT_TRUE(h.shouldSend(true));
  EXPECT_EQ(h.enableLosses(), 1u);
  h.sent(true, 4);
  EXPECT_FALSE(h.shouldSend(true));
}

TEST(LinkDoubt, ErrorUntilEnoughGoodSamplesAndReportedOnce) {
  LinkDoubt doubt(3);
  EXPECT_FALSE(doubt.inDoubt());
  doubt.onSample(EncoderEvent::kBoardRebooted, "rebooted");
  EXPECT_TRUE(doubt.inDoubt());
  EXPECT_EQ(doubt.cause(), "rebooted");
  doubt.onSample(EncoderEvent::kAccepted, "");
  doubt.onSample(EncoderEvent::kAccepted, "");
  doubt.onSample(EncoderEvent::kImplausibleJump, "jump");  // not healthy yet: start over
  doubt.onSample(EncoderEvent::kAccepted, "");
  doubt.onSample(EncoderEvent::kAccepted, "");
  EXPECT_TRUE(doubt.inDoubt());
  doubt.onSample(EncoderEvent::kAccepted, "");
  // Healthy again, but no diagnostics update has shown the doubt yet: it stays until one has.
  EXPECT_TRUE(doubt.inDoubt());
  EXPECT_TRUE(doubt.report());
  EXPECT_FALSE(doubt.inDoubt());
  EXPECT_FALSE(doubt.report());
}

TEST(LinkDoubt, EveryRebootClaimCastsDoubt) {
  for (EncoderEvent e : {EncoderEvent::kRebootPending, EncoderEvent::kRebootRefuted, EncoderEvent::kRebootImplausible,
                         EncoderEvent::kBoardRebooted, EncoderEvent::kRebaselined}) {
    LinkDoubt doubt(1);
    doubt.onSample(e, "why");
    EXPECT_TRUE(doubt.report()) << static_cast<int>(e);
  }
  for (EncoderEvent e : {EncoderEvent::kAccepted, EncoderEvent::kBaseline, EncoderEvent::kImplausibleJump,
                         EncoderEvent::kClockJumped, EncoderEvent::kWrongWheelCount}) {
    LinkDoubt doubt(1);
    doubt.onSample(e, "why");
    EXPECT_FALSE(doubt.report()) << static_cast<int>(e);
  }
}

// Issue 12: a fast board reboot while driving. The host loop is the node's (serial backend + encoder
// path) on the core classes: the reboot must be detected, ENABLE re-sent so the wheels turn again,
// health ERROR until it is over, and /odom must not jump.
TEST(BoardSession, FastRebootWhileDrivingIsRecoveredWithoutAnOdometryJump) {
  FakeMotorBoardConfig board_cfg;
  board_cfg.drive.volts_per_rad_s = 0.55;
  board_cfg.counts_per_rev = 1320.0;
  FakeMotorBoard board(board_cfg);
  const OmniKinematics kinematics(WheelLayout{{0.0, 2.0 * M_PI / 3.0, 4.0 * M_PI / 3.0}, 0.10, 0.024});
  EncoderTrackerConfig tracker_cfg;
  tracker_cfg.counts_per_rev = 1320.0;
  tracker_cfg.max_plausible_rad_s = 2.0 * board_cfg.drive.maxSpeed();
  EncoderTracker tracker(tracker_cfg);
  EnableHandshake enable;
  LinkDoubt doubt;
  OdometryIntegrator odometry;
  protocol::StreamDecoder host;

  const auto wheel_rad_s = kinematics.inverse({0.2, 0.0, 0.0});
  std::vector<int16_t> duty;
  for (double w : wheel_rad_s) {
    duty.push_back(static_cast<int16_t>(std::lround(board_cfg.drive.dutyFromSpeed(w) * protocol::kDutyFullScale)));
  }
  const int reboot_cycle = 100;  // 2 s in
  double largest_step_at_reboot = -1.0;
  bool recovering_after_reboot = false;
  uint8_t sequence = 0;
  for (int cycle = 0; cycle < 250; ++cycle) {
    const double t = 0.02 * cycle;
    board.advanceTo(t);
    if (cycle == reboot_cycle) board.resetCounters();
    std::vector<uint8_t> bytes;
    if (enable.shouldSend(true)) {
      bytes = protocol::encodeFrame(protocol::makeEnableFrame({sequence, true}));
      enable.sent(true, sequence++);
    }
    const auto duty_bytes = protocol::encodeFrame(protocol::makeDutyFrame({sequence++, duty}));
    bytes.insert(bytes.end(), duty_bytes.begin(), duty_bytes.end());
    const auto reply = board.receive(bytes.data(), bytes.size(), t);
    for (const auto& frame : host.feed(reply.data(), reply.size())) {
      const auto state = protocol::parseStateFrame(frame);
      ASSERT_TRUE(state);
      enable.onBoardState(state->sequence, (state->status & protocol::kStatusEnabled) != 0);
      const auto sample = tracker.update(EncoderFrame{state->encoder_counts, state->board_time_ms, t + 0.001});
      doubt.onSample(sample.event, sample.reason);
      if (sample.event == EncoderEvent::kRebootPending) enable.forceResend();
      if (!sample.accepted()) continue;
      const Pose2D before = odometry.pose();
      odometry.integrateDisplacement(kinematics.forward(sample.delta_rad));
      if (sample.event == EncoderEvent::kBoardRebooted) {
        largest_step_at_reboot = std::hypot(odometry.pose().x - before.x, odometry.pose().y - before.y);
        recovering_after_reboot = doubt.inDoubt();
      }
    }
  }
  EXPECT_EQ(tracker.reboots(), 1u);
  EXPECT_GE(largest_step_at_reboot, 0.0) << "the reboot was not detected";
  // The step at the confirmation carries the motion of the held frames (at most 0.2 m/s over them), no jump.
  EXPECT_LE(largest_step_at_reboot, 0.2 * 0.02 * (EncoderTracker::kRebootConfirmationFrames + 1) + 1e-3);
  EXPECT_TRUE(recovering_after_reboot);
  EXPECT_TRUE(doubt.report());   // never shown yet
  EXPECT_FALSE(doubt.inDoubt());  // 3 s of good samples later, and reported
  EXPECT_TRUE(board.enabled()) << "ENABLE was not sent again after the reboot";
  EXPECT_NEAR(board.wheelSpeeds()[0], wheel_rad_s[0], 0.05 * std::abs(wheel_rad_s[0]));
  // Distance: 0.2 m/s for 5 s, less what the wheels did not do while the rebooted board was disabled
  // (one cycle) and the motor lag twice; no jump either way.
  EXPECT_NEAR(odometry.pose().x, 0.2 * 4.98, 0.03);
  EXPECT_NEAR(odometry.pose().y, 0.0, 0.005);
}
