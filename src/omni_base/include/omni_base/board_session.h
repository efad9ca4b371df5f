// Keeping the motor board in the state the driver wants across board reboots (ROS-free).
#pragma once

#include <cstdint>
#include <string>

#include "omni_base/encoder_tracker.h"

namespace omni_base {

/// Decides when to send ENABLE: on connect, on every change, and whenever the board reports the other
/// state in answer to a command sent after our last ENABLE. A board that rebooted starts disabled, so
/// without this a fast reboot leaves it unpowered while the host streams duties that turn nothing.
class EnableHandshake {
 public:
  /// A new connection (or a detected reboot): the next cycle sends ENABLE whatever the board says.
  void forceResend() { must_send_ = true; }
  bool shouldSend(bool want_enabled) const { return must_send_ || mismatch_ || !sent_ || want_enabled != sent_state_; }
  void sent(bool enabled, uint8_t sequence);
  /// A STATE frame answering command `answered_sequence` says whether the board is enabled.
  void onBoardState(uint8_t answered_sequence, bool board_enabled);

  /// The board reports the state we last sent.
  bool confirmed() const { return sent_ && confirmed_; }
  /// The board reported the other state after confirming ours (a reboot, a brown-out).
  std::uint64_t enableLosses() const { return enable_losses_; }

 private:
  bool sent_{false};
  bool sent_state_{false};
  uint8_t sent_sequence_{0};
  bool must_send_{true};
  bool mismatch_{false};
  bool confirmed_{false};
  std::uint64_t enable_losses_{0};
};

/// Whether the link's odometry is in doubt: after a reboot (claimed, confirmed, refuted or refused) or a
/// re-baseline, diagnostics report ERROR until `healthy_samples` accepted samples have come in a row AND
/// the doubt has been reported at least once, so that a diagnostics period longer than the recovery
/// still shows it.
class LinkDoubt {
 public:
  static constexpr int kDefaultHealthySamples = 25;  // 0.5 s at 50 Hz

  explicit LinkDoubt(int healthy_samples = kDefaultHealthySamples) : healthy_samples_(healthy_samples) {}
  void onSample(EncoderEvent event, const std::string& reason);
  bool inDoubt() const { return good_in_a_row_ < healthy_samples_ || !reported_; }
  /// Diagnostics call this when they publish: true while in doubt (the doubt then counts as reported).
  bool report();
  /// What raised the doubt last.
  const std::string& cause() const { return cause_; }

 private:
  int healthy_samples_;
  int good_in_a_row_{healthy_samples_};
  bool reported_{true};
  std::string cause_;
};

}  // namespace omni_base
