#include "omni_base/motor_protocol.h"

#include <algorithm>
#include <stdexcept>

namespace omni_base {
namespace protocol {
namespace {

void putU16(std::vector<uint8_t>& out, uint16_t v) {
  out.push_back(static_cast<uint8_t>(v & 0xFF));
  out.push_back(static_cast<uint8_t>(v >> 8));
}

void putU32(std::vector<uint8_t>& out, uint32_t v) {
  for (int shift = 0; shift < 32; shift += 8) out.push_back(static_cast<uint8_t>((v >> shift) & 0xFF));
}

uint16_t getU16(const uint8_t* p) { return static_cast<uint16_t>(p[0] | (p[1] << 8)); }

uint32_t getU32(const uint8_t* p) {
  return static_cast<uint32_t>(p[0]) | (static_cast<uint32_t>(p[1]) << 8) | (static_cast<uint32_t>(p[2]) << 16) |
         (static_cast<uint32_t>(p[3]) << 24);
}

}  // namespace

uint16_t crc16(const uint8_t* data, std::size_t size) {
  uint16_t crc = 0xFFFF;
  for (std::size_t i = 0; i < size; ++i) {
    crc ^= static_cast<uint16_t>(data[i]) << 8;
    for (int bit = 0; bit < 8; ++bit) {
      crc = (crc & 0x8000) ? static_cast<uint16_t>((crc << 1) ^ 0x1021) : static_cast<uint16_t>(crc << 1);
    }
  }
  return crc;
}

std::vector<uint8_t> encodeFrame(const Frame& frame) {
  if (frame.payload.size() > kMaxPayload) {
    throw std::invalid_argument("motor protocol payload of " + std::to_string(frame.payload.size()) +
                                " bytes exceeds the maximum of " + std::to_string(kMaxPayload));
  }
  std::vector<uint8_t> out;
  out.reserve(kHeaderSize + frame.payload.size() + kCrcSize);
  out.push_back(kStart1);
  out.push_back(kStart2);
  out.push_back(frame.type);
  out.push_back(static_cast<uint8_t>(frame.payload.size()));
  out.insert(out.end(), frame.payload.begin(), frame.payload.end());
  putU16(out, crc16(out.data() + 2, out.size() - 2));
  return out;
}

Frame makeDutyFrame(const DutyCommand& command) {
  if (command.duty.size() > kMaxWheels) throw std::invalid_argument("too many wheels for the motor protocol");
  Frame f{static_cast<uint8_t>(FrameType::kSetDuty), {}};
  f.payload.push_back(command.sequence);
  f.payload.push_back(static_cast<uint8_t>(command.duty.size()));
  for (int16_t d : command.duty) putU16(f.payload, static_cast<uint16_t>(d));
  return f;
}

Frame makeEnableFrame(const EnableCommand& command) {
  return Frame{static_cast<uint8_t>(FrameType::kEnable), {command.sequence, static_cast<uint8_t>(command.enable ? 1 : 0)}};
}

Frame makeStateFrame(const BoardState& state) {
  if (state.encoder_counts.size() > kMaxWheels) throw std::invalid_argument("too many wheels for the motor protocol");
  Frame f{static_cast<uint8_t>(FrameType::kState), {}};
  f.payload = {state.sequence, state.status, state.faults, static_cast<uint8_t>(state.encoder_counts.size())};
  for (int32_t c : state.encoder_counts) putU32(f.payload, static_cast<uint32_t>(c));
  putU32(f.payload, state.board_time_ms);
  return f;
}

std::optional<DutyCommand> parseDutyFrame(const Frame& frame) {
  if (frame.type != static_cast<uint8_t>(FrameType::kSetDuty) || frame.payload.size() < 2) return std::nullopt;
  const std::size_t n = frame.payload[1];
  if (n > kMaxWheels || frame.payload.size() != 2 + 2 * n) return std::nullopt;
  DutyCommand c;
  c.sequence = frame.payload[0];
  for (std::size_t i = 0; i < n; ++i) {
    c.duty.push_back(static_cast<int16_t>(getU16(&frame.payload[2 + 2 * i])));
  }
  return c;
}

std::optional<EnableCommand> parseEnableFrame(const Frame& frame) {
  if (frame.type != static_cast<uint8_t>(FrameType::kEnable) || frame.payload.size() != 2) return std::nullopt;
  if (frame.payload[1] > 1) return std::nullopt;
  return EnableCommand{frame.payload[0], frame.payload[1] == 1};
}

std::optional<BoardState> parseStateFrame(const Frame& frame) {
  if (frame.type != static_cast<uint8_t>(FrameType::kState) || frame.payload.size() < 4) return std::nullopt;
  const std::size_t n = frame.payload[3];
  if (n > kMaxWheels || frame.payload.size() != 4 + 4 * n + 4) return std::nullopt;
  BoardState s;
  s.sequence = frame.payload[0];
  s.status = frame.payload[1];
  s.faults = frame.payload[2];
  for (std::size_t i = 0; i < n; ++i) s.encoder_counts.push_back(static_cast<int32_t>(getU32(&frame.payload[4 + 4 * i])));
  s.board_time_ms = getU32(&frame.payload[4 + 4 * n]);
  return s;
}

std::vector<Frame> StreamDecoder::feed(const uint8_t* data, std::size_t size) {
  buffer_.insert(buffer_.end(), data, data + size);
  std::vector<Frame> frames;
  std::size_t pos = 0;
  while (true) {
    // Find the start sequence; everything before it is garbage.
    std::size_t start = pos;
    while (start + 1 < buffer_.size() && !(buffer_[start] == kStart1 && buffer_[start + 1] == kStart2)) ++start;
    if (start + 1 >= buffer_.size()) {
      // Keep a trailing kStart1: it may be the first half of a start sequence.
      const std::size_t keep_from = (!buffer_.empty() && buffer_.back() == kStart1 && start < buffer_.size()) ? buffer_.size() - 1 : buffer_.size();
      garbage_bytes_ += keep_from - pos;
      pos = keep_from;
      break;
    }
    garbage_bytes_ += start - pos;
    pos = start;
    if (buffer_.size() - pos < kHeaderSize) break;  // wait for the header
    const std::size_t length = buffer_[pos + 3];
    if (length > kMaxPayload) {
      ++length_errors_;
      ++garbage_bytes_;
      pos += 1;  // a false start: search again from the next byte
      continue;
    }
    const std::size_t total = kHeaderSize + length + kCrcSize;
    if (buffer_.size() - pos < total) break;  // wait for the rest
    const uint16_t expected = crc16(&buffer_[pos + 2], 2 + length);
    const uint16_t received = getU16(&buffer_[pos + kHeaderSize + length]);
    if (expected != received) {
      ++crc_errors_;
      ++garbage_bytes_;
      pos += 1;
      continue;
    }
    Frame f;
    f.type = buffer_[pos + 2];
    f.payload.assign(buffer_.begin() + static_cast<std::ptrdiff_t>(pos + kHeaderSize),
                     buffer_.begin() + static_cast<std::ptrdiff_t>(pos + kHeaderSize + length));
    frames.push_back(std::move(f));
    ++frames_decoded_;
    pos += total;
  }
  buffer_.erase(buffer_.begin(), buffer_.begin() + static_cast<std::ptrdiff_t>(pos));
  return frames;
}

}  // namespace protocol
}  // namespace omni_base
