#include "omni_base/serial_fuzz.h"

#include <algorithm>
#include <cstdlib>
#include <random>

#include "omni_base/motor_protocol.h"

namespace omni_base {
namespace serial_fuzz {
namespace {

using protocol::Frame;

constexpr int kMaxCorruptions = 4;           // 1..4 bit flips or byte replacements per frame
constexpr std::size_t kMaxReportedViolations = 10;
constexpr std::size_t kFramesPerStreamMax = 4;
constexpr std::size_t kGarbageRunMax = 40;
constexpr double kFalseStartProbability = 0.3;  // a garbage run holds a start sequence this often

const std::vector<uint8_t>& zeroDutyFrameBytes() {
  static const std::vector<uint8_t> bytes =
      protocol::encodeFrame(protocol::makeDutyFrame(protocol::DutyCommand{0, {0, 0, 0}}));
  return bytes;
}

bool movesAWheel(const Frame& frame) {
  const auto duty = protocol::parseDutyFrame(frame);
  return duty && std::any_of(duty->duty.begin(), duty->duty.end(), [](int16_t d) { return d != 0; });
}

std::vector<uint8_t> corrupt(const std::vector<uint8_t>& clean, bool bit_flips, std::mt19937& rng) {
  std::vector<uint8_t> bytes = clean;
  const int count = std::uniform_int_distribution<int>(1, kMaxCorruptions)(rng);
  std::uniform_int_distribution<std::size_t> position(0, bytes.size() - 1);
  std::uniform_int_distribution<int> value(0, 255);
  if (bit_flips) {
    // Distinct bits, so that n flips really change n bits.
    std::vector<std::size_t> bits;
    std::uniform_int_distribution<std::size_t> bit(0, bytes.size() * 8 - 1);
    while (bits.size() < static_cast<std::size_t>(count)) {
      const std::size_t b = bit(rng);
      if (std::find(bits.begin(), bits.end(), b) == bits.end()) bits.push_back(b);
    }
    for (std::size_t b : bits) bytes[b / 8] ^= static_cast<uint8_t>(1u << (b % 8));
  } else {
    for (int i = 0; i < count; ++i) bytes[position(rng)] = static_cast<uint8_t>(value(rng));
  }
  return bytes;
}

/// A valid frame of a random kind: SET_DUTY with in-range duties, ENABLE, STATE, or an unknown type.
Frame randomValidFrame(std::mt19937& rng) {
  std::uniform_int_distribution<int> byte(0, 255);
  std::uniform_int_distribution<int> wheels(1, static_cast<int>(protocol::kMaxWheels));
  switch (std::uniform_int_distribution<int>(0, 3)(rng)) {
    case 0: {
      protocol::DutyCommand c{static_cast<uint8_t>(byte(rng)), {}};
      std::uniform_int_distribution<int> duty(-protocol::kDutyFullScale, protocol::kDutyFullScale);
      c.duty.resize(static_cast<std::size_t>(wheels(rng)));
      for (auto& d : c.duty) d = static_cast<int16_t>(duty(rng));
      return protocol::makeDutyFrame(c);
    }
    case 1:
      return protocol::makeEnableFrame({static_cast<uint8_t>(byte(rng)), byte(rng) % 2 == 0});
    case 2: {
      protocol::BoardState s;
      s.sequence = static_cast<uint8_t>(byte(rng));
      s.status = static_cast<uint8_t>(byte(rng));
      s.encoder_counts.resize(static_cast<std::size_t>(wheels(rng)));
      for (auto& c : s.encoder_counts) c = static_cast<int32_t>(rng());
      s.board_time_ms = static_cast<uint32_t>(rng());
      return protocol::makeStateFrame(s);
    }
    default: {
      Frame f{static_cast<uint8_t>(0x40 + byte(rng) % 0x20), {}};
      f.payload.resize(std::uniform_int_distribution<std::size_t>(0, protocol::kMaxPayload)(rng));
      for (auto& b : f.payload) b = static_cast<uint8_t>(byte(rng));
      return f;
    }
  }
}

void appendGarbage(std::vector<uint8_t>& stream, std::mt19937& rng) {
  std::uniform_int_distribution<int> byte(0, 255);
  const std::size_t n = std::uniform_int_distribution<std::size_t>(0, kGarbageRunMax)(rng);
  const bool false_start = std::uniform_real_distribution<double>(0.0, 1.0)(rng) < kFalseStartProbability;
  const std::size_t start_at = n == 0 ? 0 : std::uniform_int_distribution<std::size_t>(0, n - 1)(rng);
  for (std::size_t i = 0; i < n; ++i) {
    if (false_start && i == start_at) {
      // A false header whose announced length usually runs into the next valid frame.
      stream.push_back(protocol::kStart1);
      stream.push_back(protocol::kStart2);
      stream.push_back(static_cast<uint8_t>(byte(rng)));
      stream.push_back(static_cast<uint8_t>(byte(rng) % (protocol::kMaxPayload + 8)));
    } else {
      stream.push_back(static_cast<uint8_t>(byte(rng)));
    }
  }
}

bool sameFrame(const Frame& a, const Frame& b) { return a.type == b.type && a.payload == b.payload; }

void checkDecodedFrame(const Frame& f, const std::vector<uint8_t>& stream, StreamFuzzResult& result) {
  auto violation = [&result](const std::string& what) {
    if (result.violations.size() < kMaxReportedViolations) result.violations.push_back(what);
  };
  // Its exact encoding (so its check value) must be in the stream: no frame with a bad check value.
  const auto bytes = protocol::encodeFrame(f);
  if (std::search(stream.begin(), stream.end(), bytes.begin(), bytes.end()) == stream.end()) {
    violation("input " + std::to_string(result.inputs) + ": a decoded frame is not in the stream verbatim");
  }
  if (const auto duty = protocol::parseDutyFrame(f)) {
    for (int16_t d : duty->duty) {
      if (std::abs(d) > protocol::kDutyFullScale) {
        violation("input " + std::to_string(result.inputs) + ": duty " + std::to_string(d) + " out of range");
      }
    }
  }
}

}  // namespace

CorruptionResult runCorruptionBenchmark(std::uint64_t frames, std::uint32_t seed) {
  std::mt19937 rng(seed);
  CorruptionResult result;
  const auto& clean = zeroDutyFrameBytes();
  for (std::uint64_t i = 0; i < frames; ++i) {
    const bool bit_flips = (i % 2) == 0;
    std::vector<uint8_t> stream = corrupt(clean, bit_flips, rng);
    stream.insert(stream.end(), clean.begin(), clean.end());
    protocol::StreamDecoder decoder;
    const auto decoded = decoder.feed(stream.data(), stream.size());
    ++result.corrupted_frames;
    ++(bit_flips ? result.bit_flip_frames : result.byte_replace_frames);
    result.decoded_frames += decoded.size();
    bool clean_found = false;
    for (const auto& f : decoded) {
      if (movesAWheel(f)) ++result.nonzero_duty;
      if (protocol::encodeFrame(f) == clean) clean_found = true;
    }
    if (!clean_found) ++result.clean_frames_lost;
  }
  return result;
}

StreamFuzzResult runStreamFuzz(std::uint64_t inputs, std::uint32_t seed) {
  std::mt19937 rng(seed);
  StreamFuzzResult result;
  for (std::uint64_t i = 0; i < inputs; ++i) {
    std::vector<uint8_t> stream;
    std::vector<Frame> embedded;
    const std::size_t count = std::uniform_int_distribution<std::size_t>(0, kFramesPerStreamMax)(rng);
    for (std::size_t k = 0; k < count; ++k) {
      appendGarbage(stream, rng);
      embedded.push_back(randomValidFrame(rng));
      const auto bytes = protocol::encodeFrame(embedded.back());
      stream.insert(stream.end(), bytes.begin(), bytes.end());
    }
    appendGarbage(stream, rng);
    // Then one frame's worth of idle line: a good frame holding a start sequence near its end may wait
    // for the bytes that frame announces (see StreamDecoder); they come with the next frame on a live link.
    stream.insert(stream.end(), protocol::kHeaderSize + protocol::kMaxPayload + protocol::kCrcSize, 0x00);
    // Feed in random chunks, as a serial port delivers them.
    protocol::StreamDecoder decoder;
    std::vector<Frame> decoded;
    for (std::size_t at = 0; at < stream.size();) {
      const std::size_t n = std::min(stream.size() - at, std::uniform_int_distribution<std::size_t>(1, 32)(rng));
      const auto got = decoder.feed(stream.data() + at, n);
      decoded.insert(decoded.end(), got.begin(), got.end());
      at += n;
    }
    ++result.inputs;
    result.embedded_frames += embedded.size();
    // Every embedded frame must come out, in order; anything else decoded is an extra.
    std::size_t next = 0;
    for (const auto& f : decoded) {
      checkDecodedFrame(f, stream, result);
      if (next < embedded.size() && sameFrame(f, embedded[next])) {
        ++next;
      } else {
        ++result.extra_frames;
      }
    }
    result.found_frames += next;
    if (next != embedded.size() && result.violations.size() < kMaxReportedViolations) {
      result.violations.push_back("input " + std::to_string(i) + ": found " + std::to_string(next) + " of " +
                                  std::to_string(embedded.size()) + " embedded frames");
    }
  }
  return result;
}

}  // namespace serial_fuzz
}  // namespace omni_base
