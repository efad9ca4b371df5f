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

uint32_t crc32c(const uint8_t* data, std::size_t size) {
  // Bitwise, reflected: frames are at most 70 bytes, and the board firmware can use the same loop.
  constexpr uint32_t kReflectedPolynomial = 0x82F63B78u;
  uint32_t crc = 0xFFFFFFFFu;
  for (std::size_t i = 0; i < size; ++i) {
    crc ^= data[i];
    for (int bit = 0; bit < 8; ++bit) crc = (crc & 1u) ? (crc >> 1) ^ kReflectedPolynomial : crc >> 1;
  }
  return crc ^ 0xFFFFFFFFu;
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
  putU32(out, crc32c(out.data() + 2, out.size() - 2));
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
    const auto duty = static_cast<int16_t>(getU16(&frame.payload[2 + 2 * i]));
    if (duty > kDutyFullScale || duty < -kDutyFullScale) return std::nullopt;  // corrupt, not a command
    c.duty.push_back(duty);
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

std::optional<std::size_t> StreamDecoder::frameLengthAt(std::size_t pos) const {
  if (buffer_.size() - pos < kHeaderSize || buffer_[pos] != kStart1 || buffer_[pos + 1] != kStart2) return std::nullopt;
  const std::size_t length = buffer_[pos + 3];
  if (length > kMaxPayload) return std::nullopt;
  return kHeaderSize + length + kCrcSize;
}

bool StreamDecoder::crcValidAt(std::size_t pos, std::size_t total) const {
  const std::size_t covered = total - 2 - kCrcSize;  // type, length and payload
  return crc32c(&buffer_[pos + 2], covered) == getU32(&buffer_[pos + total - kCrcSize]);
}

std::optional<std::size_t> StreamDecoder::findValidFrame(std::size_t from, std::size_t to) const {
  for (std::size_t q = from; q < to; ++q) {
    const auto total = frameLengthAt(q);
    if (total && buffer_.size() - q >= *total && crcValidAt(q, *total)) return q;
  }
  return std::nullopt;
}

bool StreamDecoder::incompleteFrameStarts(std::size_t from, std::size_t to) const {
  // Only a whole, sane header counts: a start sequence in the last bytes of a good frame must not hold
  // it back until more bytes arrive (the board may have nothing more to send).
  for (std::size_t q = from; q < to; ++q) {
    const auto total = frameLengthAt(q);
    if (total && buffer_.size() - q < *total) return true;
  }
  return false;
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
    const auto total = frameLengthAt(pos);
    if (!total) {
      ++length_errors_;
      ++garbage_bytes_;
      pos += 1;  // a false start: search again from the next byte
      continue;
    }
    const std::size_t span_end = std::min(pos + *total, buffer_.size());
    // A complete valid frame inside this candidate's span means the candidate is a false start (valid
    // by chance, or announcing more bytes than will come before the next frame).
    if (const auto inner = findValidFrame(pos + 1, span_end)) {
      ++false_starts_;
      garbage_bytes_ += *inner - pos;
      pos = *inner;
      continue;
    }
    if (buffer_.size() - pos < *total) break;  // wait for the rest
    if (!crcValidAt(pos, *total)) {
      ++crc_errors_;
      ++garbage_bytes_;
      pos += 1;
      continue;
    }
    // Valid, but a frame starting inside it is still arriving: it could overrule this one, so wait.
    if (incompleteFrameStarts(pos + 1, pos + *total)) break;
    const std::size_t length = *total - kHeaderSize - kCrcSize;
    Frame f;
    f.type = buffer_[pos + 2];
    f.payload.assign(buffer_.begin() + static_cast<std::ptrdiff_t>(pos + kHeaderSize),
                     buffer_.begin() + static_cast<std::ptrdiff_t>(pos + kHeaderSize + length));
    frames.push_back(std::move(f));
    ++frames_decoded_;
    pos += *total;
  }
  buffer_.erase(buffer_.begin(), buffer_.begin() + static_cast<std::ptrdiff_t>(pos));
  return frames;
}

}  // namespace protocol
}  // namespace omni_base
