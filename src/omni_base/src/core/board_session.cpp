#include "omni_base/board_session.h"

namespace omni_base {

void EnableHandshake::sent(bool enabled, uint8_t sequence) {
  sent_ = true;
  sent_state_ = enabled;
  sent_sequence_ = sequence;
  must_send_ = false;
  mismatch_ = false;
  confirmed_ = false;
}

void EnableHandshake::onBoardState(uint8_t answered_sequence, bool board_enabled) {
  if (!sent_) return;
  // Sequences wrap at 256: an answer to a command sent before our ENABLE says nothing about it.
  if (static_cast<int8_t>(static_cast<uint8_t>(answered_sequence - sent_sequence_)) < 0) return;
  if (board_enabled == sent_state_) {
    confirmed_ = true;
    return;
  }
  if (confirmed_) ++enable_losses_;
  confirmed_ = false;
  mismatch_ = true;
}

void RebootRecovery::onSample(EncoderEvent event) {
  switch (event) {
    case EncoderEvent::kBoardRebooted:
      ++reboots_;
      good_in_a_row_ = 0;
      break;
    case EncoderEvent::kRebaselined:
      good_in_a_row_ = 0;
      break;
    case EncoderEvent::kAccepted:
      if (good_in_a_row_ < healthy_samples_) ++good_in_a_row_;
      break;
    case EncoderEvent::kBaseline:
      break;
    case EncoderEvent::kWrongWheelCount:
    case EncoderEvent::kImplausibleJump:
    case EncoderEvent::kClockJumped:
    case EncoderEvent::kClockBackwards:
      if (recovering()) good_in_a_row_ = 0;
      break;
  }
}

}  // namespace omni_base
