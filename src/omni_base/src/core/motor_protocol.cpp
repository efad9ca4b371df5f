#include "omni_base/motor_protocol.h"

#include <stdexcept>
#include <string>

namespace omni_base {
namespace protocol {

std::vector<uint8_t> encodeFrame(const Frame& frame) {
  if (frame.payload.size() > kMaxPayload) {
    throw std::invalid_argument("motor protocol payload of " + std::to_string(frame.payload.size()) +
                                " bytes exceeds the maximum of " + std::to_string(kMaxPayload));
  }
  std::vector<uint8_t> out(kHeaderSize + frame.payload.size() + kCrcSize);
  mp_encode_frame(out.data(), frame.type, frame.payload.data(), frame.payload.size());
  return out;
}

Frame makeDutyFrame(const DutyCommand& command) {
  if (command.duty.size() > kMaxWheels) throw std::invalid_argument("too many wheels for the motor protocol");
  Frame f{static_cast<uint8_t>(FrameType::kSetDuty), std::vector<uint8_t>(MP_SET_DUTY_SIZE(command.duty.size()))};
  f.payload[MP_SET_DUTY_SEQUENCE] = command.sequence;
  f.payload[MP_SET_DUTY_COUNT] = static_cast<uint8_t>(command.duty.size());
  for (std::size_t i = 0; i < command.duty.size(); ++i) {
    mp_put_u16le(&f.payload[MP_SET_DUTY_DUTIES + 2 * i], static_cast<uint16_t>(command.duty[i]));
  }
  return f;
}

Frame makeEnableFrame(const EnableCommand& command) {
  Frame f{static_cast<uint8_t>(FrameType::kEnable), std::vector<uint8_t>(MP_ENABLE_SIZE)};
  f.payload[MP_ENABLE_SEQUENCE] = command.sequence;
  f.payload[MP_ENABLE_FLAG] = static_cast<uint8_t>(command.enable ? 1 : 0);
  return f;
}

Frame makeStateFrame(const BoardState& state) {
  const std::size_t n = state.encoder_counts.size();
  if (n > kMaxWheels) throw std::invalid_argument("too many wheels for the motor protocol");
  Frame f{static_cast<uint8_t>(FrameType::kState), std::vector<uint8_t>(MP_STATE_SIZE(n))};
  f.payload[MP_STATE_SEQUENCE] = state.sequence;
  f.payload[MP_STATE_STATUS] = state.status;
  f.payload[MP_STATE_FAULTS] = state.faults;
  f.payload[MP_STATE_COUNT] = static_cast<uint8_t>(n);
  for (std::size_t i = 0; i < n; ++i) {
    mp_put_u32le(&f.payload[MP_STATE_COUNTS + 4 * i], static_cast<uint32_t>(state.encoder_counts[i]));
  }
  mp_put_u32le(&f.payload[MP_STATE_TIME(n)], state.board_time_ms);
  return f;
}

std::optional<DutyCommand> parseDutyFrame(const Frame& frame) {
  if (frame.type != MP_TYPE_SET_DUTY || frame.payload.size() < MP_SET_DUTY_SIZE(0)) return std::nullopt;
  const std::size_t n = frame.payload[MP_SET_DUTY_COUNT];
  if (n > kMaxWheels || frame.payload.size() != MP_SET_DUTY_SIZE(n)) return std::nullopt;
  DutyCommand c;
  c.sequence = frame.payload[MP_SET_DUTY_SEQUENCE];
  for (std::size_t i = 0; i < n; ++i) {
    const auto duty = static_cast<int16_t>(mp_get_u16le(&frame.payload[MP_SET_DUTY_DUTIES + 2 * i]));
    if (duty > kDutyFullScale || duty < -kDutyFullScale) return std::nullopt;  // corrupt, not a command
    c.duty.push_back(duty);
  }
  return c;
}

std::optional<EnableCommand> parseEnableFrame(const Frame& frame) {
  if (frame.type != MP_TYPE_ENABLE || frame.payload.size() != MP_ENABLE_SIZE) return std::nullopt;
  if (frame.payload[MP_ENABLE_FLAG] > 1) return std::nullopt;
  return EnableCommand{frame.payload[MP_ENABLE_SEQUENCE], frame.payload[MP_ENABLE_FLAG] == 1};
}

std::optional<BoardState> parseStateFrame(const Frame& frame) {
  if (frame.type != MP_TYPE_STATE || frame.payload.size() < MP_STATE_COUNTS) return std::nullopt;
  const std::size_t n = frame.payload[MP_STATE_COUNT];
  if (n > kMaxWheels || frame.payload.size() != MP_STATE_SIZE(n)) return std::nullopt;
  BoardState s;
  s.sequence = frame.payload[MP_STATE_SEQUENCE];
  s.status = frame.payload[MP_STATE_STATUS];
  s.faults = frame.payload[MP_STATE_FAULTS];
  for (std::size_t i = 0; i < n; ++i) {
    s.encoder_counts.push_back(static_cast<int32_t>(mp_get_u32le(&frame.payload[MP_STATE_COUNTS + 4 * i])));
  }
  s.board_time_ms = mp_get_u32le(&frame.payload[MP_STATE_TIME(n)]);
  return s;
}

void StreamDecoder::accumulateCounters(const mp_decoder& before) {
  // Unsigned differences stay right across a wrap of the 32-bit counters.
  frames_decoded_ += static_cast<uint32_t>(decoder_.frames - before.frames);
  crc_errors_ += static_cast<uint32_t>(decoder_.crc_errors - before.crc_errors);
  garbage_bytes_ += static_cast<uint32_t>(decoder_.garbage_bytes - before.garbage_bytes);
  length_errors_ += static_cast<uint32_t>(decoder_.length_errors - before.length_errors);
  false_starts_ += static_cast<uint32_t>(decoder_.false_starts - before.false_starts);
}

std::vector<Frame> StreamDecoder::feed(const uint8_t* data, std::size_t size) {
  std::vector<Frame> frames;
  std::size_t taken = 0;
  do {
    const mp_decoder before = decoder_;
    taken += mp_decoder_put(&decoder_, data + taken, size - taken);
    mp_frame frame;
    while (mp_decoder_next(&decoder_, &frame)) {
      frames.push_back(Frame{frame.type, std::vector<uint8_t>(frame.payload, frame.payload + frame.length)});
    }
    accumulateCounters(before);
  } while (taken < size);
  return frames;
}

}  // namespace protocol
}  // namespace omni_base
