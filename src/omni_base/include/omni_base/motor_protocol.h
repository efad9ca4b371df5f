// The binary protocol between omni_base and the motor board (ROS-free): C++ types over the one home
// of the wire format, omni_base/motor_wire.h (frame layout, ids, limits, CRC-32C, stream decoder), which
// the AVR firmware compiles too. Specified for firmware authors in src/omni_base/README.md, "Motor
// board protocol".
//
// Frame: 0xA5 0x5A | type (u8) | length N (u8, 0..kMaxPayload) | payload (N bytes) | CRC-32C (u32 LE)
// The CRC is CRC-32C (Castagnoli, reflected poly 0x82F63B78, init and final XOR 0xFFFFFFFF) over
// type, length and payload: Hamming distance 8 up to 177 bits and 6 up to 5243 bits, so every
// corruption of up to 5 bits in a frame is detected (CRC-16 let 4 bit flips through at ~2^-16).
// Multi-byte fields are little-endian.
#pragma once

#include <cstddef>
#include <cstdint>
#include <optional>
#include <vector>

#include "omni_base/motor_wire.h"

namespace omni_base {
namespace protocol {

constexpr uint8_t kStart1 = MP_START1;
constexpr uint8_t kStart2 = MP_START2;
constexpr std::size_t kHeaderSize = MP_HEADER_SIZE;  // start1, start2, type, length
constexpr std::size_t kCrcSize = MP_CRC_SIZE;
constexpr std::size_t kMaxPayload = MP_MAX_PAYLOAD;
constexpr std::size_t kMaxWheels = MP_MAX_WHEELS;
constexpr int16_t kDutyFullScale = MP_DUTY_FULL_SCALE;  // duty is sent in 1/10000 of the supply voltage

enum class FrameType : uint8_t {
  kSetDuty = MP_TYPE_SET_DUTY,  // host -> board: u8 sequence, u8 n, n x i16 duty (1/10000, signed, |duty| <= 10000)
  kEnable = MP_TYPE_ENABLE,     // host -> board: u8 sequence, u8 enable (0 = brake and unpower, 1 = drive)
  kState = MP_TYPE_STATE,       // board -> host: u8 sequence echoed, u8 status, u8 faults, u8 n,
                                //                n x i32 encoder counts, u32 board time (ms)
};

// Status bits of a kState frame.
constexpr uint8_t kStatusEnabled = MP_STATUS_ENABLED;                   // motors enabled
constexpr uint8_t kStatusWatchdogStopped = MP_STATUS_WATCHDOG_STOPPED;  // board stopped the motors: no command for 250 ms
constexpr uint8_t kStatusFault = MP_STATUS_FAULT;                       // see the fault bits
// Fault bits of a kState frame.
constexpr uint8_t kFaultStall = MP_FAULT_STALL;  // a wheel is commanded but does not turn
constexpr uint8_t kFaultOverCurrent = MP_FAULT_OVER_CURRENT;
constexpr uint8_t kFaultUnderVoltage = MP_FAULT_UNDER_VOLTAGE;

struct Frame {
  uint8_t type{0};
  std::vector<uint8_t> payload;
};

struct DutyCommand {
  uint8_t sequence{0};
  std::vector<int16_t> duty;  ///< per wheel, -kDutyFullScale..kDutyFullScale
};

struct EnableCommand {
  uint8_t sequence{0};
  bool enable{false};
};

struct BoardState {
  uint8_t sequence{0};
  uint8_t status{0};
  uint8_t faults{0};
  std::vector<int32_t> encoder_counts;
  uint32_t board_time_ms{0};
};

/// CRC-32C; the check value of ASCII "123456789" is 0xE3069283.
inline uint32_t crc32c(const uint8_t* data, std::size_t size) { return mp_crc32c(data, size); }

/// Serialises a frame; throws std::invalid_argument for a payload over kMaxPayload.
std::vector<uint8_t> encodeFrame(const Frame& frame);

Frame makeDutyFrame(const DutyCommand& command);
Frame makeEnableFrame(const EnableCommand& command);
Frame makeStateFrame(const BoardState& state);
std::optional<DutyCommand> parseDutyFrame(const Frame& frame);
std::optional<EnableCommand> parseEnableFrame(const Frame& frame);
std::optional<BoardState> parseStateFrame(const Frame& frame);

/// Extracts frames from a byte stream that may hold garbage, partial frames and corrupted frames: the
/// shared decoder of motor_wire.h (its rules are described there), with 64-bit counters.
class StreamDecoder {
 public:
  StreamDecoder() { mp_decoder_init(&decoder_); }
  /// Appends bytes and returns every complete, valid frame they finish.
  std::vector<Frame> feed(const uint8_t* data, std::size_t size);
  void reset() { mp_decoder_init(&decoder_); }

  std::uint64_t framesDecoded() const { return frames_decoded_; }
  std::uint64_t crcErrors() const { return crc_errors_; }
  std::uint64_t garbageBytes() const { return garbage_bytes_; }
  std::uint64_t lengthErrors() const { return length_errors_; }
  std::uint64_t falseStarts() const { return false_starts_; }  ///< candidates overruled by a frame inside them
  std::size_t buffered() const { return decoder_.size - decoder_.pos; }

 private:
  /// Adds what the shared decoder counted (32-bit, wrapping) since the last call.
  void accumulateCounters(const mp_decoder& before);

  mp_decoder decoder_;
  std::uint64_t frames_decoded_{0};
  std::uint64_t crc_errors_{0};
  std::uint64_t garbage_bytes_{0};
  std::uint64_t length_errors_{0};
  std::uint64_t false_starts_{0};
};

}  // namespace protocol
}  // namespace omni_base
