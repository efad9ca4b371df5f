// The binary protocol between omni_base and the motor board (ROS-free). Specified for firmware
// authors in src/omni_base/README.md, "Motor board protocol".
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

namespace omni_base {
namespace protocol {

constexpr uint8_t kStart1 = 0xA5;
constexpr uint8_t kStart2 = 0x5A;
constexpr std::size_t kHeaderSize = 4;     // start1, start2, type, length
constexpr std::size_t kCrcSize = 4;
constexpr std::size_t kMaxPayload = 64;
constexpr std::size_t kMaxWheels = 8;
constexpr int16_t kDutyFullScale = 10000;  // duty is sent in 1/10000 of the supply voltage

enum class FrameType : uint8_t {
  kSetDuty = 0x01,   // host -> board: u8 sequence, u8 n, n x i16 duty (1/10000, signed, |duty| <= 10000)
  kEnable = 0x02,    // host -> board: u8 sequence, u8 enable (0 = brake and unpower, 1 = drive)
  kState = 0x81,     // board -> host: u8 sequence echoed, u8 status, u8 faults, u8 n,
                     //                n x i32 encoder counts, u32 board time (ms)
};

// Status bits of a kState frame.
constexpr uint8_t kStatusEnabled = 0x01;         // motors enabled
constexpr uint8_t kStatusWatchdogStopped = 0x02; // board stopped the motors: no command for 250 ms
constexpr uint8_t kStatusFault = 0x04;           // see the fault bits
// Fault bits of a kState frame.
constexpr uint8_t kFaultStall = 0x01;            // a wheel is commanded but does not turn
constexpr uint8_t kFaultOverCurrent = 0x02;
constexpr uint8_t kFaultUnderVoltage = 0x04;

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
uint32_t crc32c(const uint8_t* data, std::size_t size);

/// Serialises a frame; throws std::invalid_argument for a payload over kMaxPayload.
std::vector<uint8_t> encodeFrame(const Frame& frame);

Frame makeDutyFrame(const DutyCommand& command);
Frame makeEnableFrame(const EnableCommand& command);
Frame makeStateFrame(const BoardState& state);
std::optional<DutyCommand> parseDutyFrame(const Frame& frame);
std::optional<EnableCommand> parseEnableFrame(const Frame& frame);
std::optional<BoardState> parseStateFrame(const Frame& frame);

/// Extracts frames from a byte stream that may hold garbage, partial frames and corrupted frames.
/// After a bad CRC or an impossible length it resumes the search one byte after the false start.
/// A false start can also look valid (its CRC matching by chance) or announce a length that runs past
/// the bytes received so far; in both cases a complete valid frame that starts inside its span wins,
/// so the false start never swallows or delays a good frame that follows it.
class StreamDecoder {
 public:
  /// Appends bytes and returns every complete, valid frame they finish.
  std::vector<Frame> feed(const uint8_t* data, std::size_t size);
  void reset() { buffer_.clear(); }

  std::uint64_t framesDecoded() const { return frames_decoded_; }
  std::uint64_t crcErrors() const { return crc_errors_; }
  std::uint64_t garbageBytes() const { return garbage_bytes_; }
  std::uint64_t lengthErrors() const { return length_errors_; }
  std::uint64_t falseStarts() const { return false_starts_; }  ///< candidates overruled by a frame inside them
  std::size_t buffered() const { return buffer_.size(); }

 private:
  std::vector<uint8_t> buffer_;
  std::uint64_t frames_decoded_{0};
  std::uint64_t crc_errors_{0};
  std::uint64_t garbage_bytes_{0};
  std::uint64_t length_errors_{0};
  std::uint64_t false_starts_{0};

  /// Where a complete frame with a valid CRC starts in [from, to), if anywhere.
  std::optional<std::size_t> findValidFrame(std::size_t from, std::size_t to) const;
  /// A whole header in [from, to) whose frame is not complete yet.
  bool incompleteFrameStarts(std::size_t from, std::size_t to) const;
  /// Length of the frame at pos if its header is there and sane, else nullopt.
  std::optional<std::size_t> frameLengthAt(std::size_t pos) const;
  bool crcValidAt(std::size_t pos, std::size_t total) const;
};

}  // namespace protocol
}  // namespace omni_base
