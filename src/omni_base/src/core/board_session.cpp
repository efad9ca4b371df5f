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

void LinkDoubt::onSample(EncoderEvent event, const std::string& reason) {
  if (castsDoubtOnTheLink(event)) {
    good_in_a_row_ = 0;
    reported_ = false;
    cause_ = reason;
  } else if (event == EncoderEvent::kAccepted) {
    if (good_in_a_row_ < healthy_samples_) ++good_in_a_row_;
  } else if (event != EncoderEvent::kBaseline && good_in_a_row_ < healthy_samples_) {
    good_in_a_row_ = 0;  // rejected while recovering: not healthy yet, start over
  }
}

bool LinkDoubt::report() {
  const bool doubt = inDoubt();
  reported_ = true;
  return doubt;
}

}  // namespace omni_base
