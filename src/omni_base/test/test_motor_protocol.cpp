#include <gtest/gtest.h>

#include <array>

#include "omni_base/motor_protocol.h"
#include "omni_base/serial_fuzz.h"

using namespace omni_base::protocol;

namespace {
std::vector<uint8_t> sampleStateBytes(uint8_t seq) {
  BoardState s;
  s.sequence = seq;
  s.status = kStatusEnabled;
  s.encoder_counts = {123456, -42, 2147483647};
  s.board_time_ms = 987654321u;
  return encodeFrame(makeStateFrame(s));
}


uint32_t readU32(const uint8_t* p) {
  return static_cast<uint32_t>(p[0]) | (static_cast<uint32_t>(p[1]) << 8) | (static_cast<uint32_t>(p[2]) << 16) |
         (static_cast<uint32_t>(p[3]) << 24);
}

/// Chooses bytes[at..at+4) so that crc32c(bytes[from..from+size)) == target. A CRC is affine in its
/// input, so the 32 free bits are solved for by Gaussian elimination over GF(2).
bool forgeCrc(std::vector<uint8_t>& bytes, std::size_t from, std::size_t size, std::size_t at, uint32_t target) {
  auto crcWith = [&](uint32_t x) {
    for (int i = 0; i < 4; ++i) bytes[at + static_cast<std::size_t>(i)] = static_cast<uint8_t>(x >> (8 * i));
    return crc32c(&bytes[from], size);
  };
  const uint32_t base = crcWith(0);
  std::array<uint32_t, 32> pivot_value{};
  std::array<uint32_t, 32> pivot_mask{};
  for (int k = 0; k < 32; ++k) {
    uint32_t v = crcWith(1u << k) ^ base;
    uint32_t m = 1u << k;
    for (int bit = 31; bit >= 0 && v != 0; --bit) {
      if (!((v >> bit) & 1u)) continue;
      if (pivot_value[static_cast<std::size_t>(bit)] == 0) {
        pivot_value[static_cast<std::size_t>(bit)] = v;
        pivot_mask[static_cast<std::size_t>(bit)] = m;
        break;
      }
      v ^= pivot_value[static_cast<std::size_t>(bit)];
      m ^= pivot_mask[static_cast<std::size_t>(bit)];
    }
  }
  uint32_t rest = target ^ base;
  uint32_t x = 0;
  for (int bit = 31; bit >= 0; --bit) {
    if (!((rest >> bit) & 1u)) continue;
    if (pivot_value[static_cast<std::size_t>(bit)] == 0) return false;
    rest ^= pivot_value[static_cast<std::size_t>(bit)];
    x ^= pivot_mask[static_cast<std::size_t>(bit)];
  }
  return crcWith(x) == target;
}

std::vector<Frame> feedByteByByte(StreamDecoder& decoder, const std::vector<uint8_t>& stream) {
  std::vector<Frame> frames;
  for (uint8_t byte : stream) {
    auto got = decoder.feed(&byte, 1);
    frames.insert(frames.end(), got.begin(), got.end());
  }
  return frames;
}

}  // namespace

TEST(MotorProtocol, CrcMatchesTheCrc32cCheckValue) {
  const std::string check = "123456789";
  EXPECT_EQ(crc32c(reinterpret_cast<const uint8_t*>(check.data()), check.size()), 0xE3069283u);
}

// A false start sequence in the garbage before a good frame, whose announced length ends inside that
// frame and whose CRC (bytes of the good frame) matches by construction: the good frame must win.
TEST(MotorProtocol, FalseStartWithAMatchingCrcDoesNotSwallowTheNextFrame) {
  const auto good = sampleStateBytes(42);
  constexpr std::size_t kFalsePayload = 4 + 10;  // 4 forged bytes, then the first 10 bytes of the good frame
  std::vector<uint8_t> stream = {kStart1, kStart2, 0x01, static_cast<uint8_t>(kFalsePayload), 0, 0, 0, 0};
  stream.insert(stream.end(), good.begin(), good.end());
  const std::size_t false_crc_at = kHeaderSize + kFalsePayload;  // inside the good frame
  ASSERT_LT(false_crc_at + kCrcSize, stream.size());
  ASSERT_TRUE(forgeCrc(stream, 2, 2 + kFalsePayload, kHeaderSize, readU32(&stream[false_crc_at])));
  ASSERT_EQ(std::vector<uint8_t>(stream.begin() + 8, stream.end()), good);  // forging left the good frame intact

  for (bool byte_by_byte : {false, true}) {
    StreamDecoder decoder;
    const auto frames = byte_by_byte ? feedByteByByte(decoder, stream) : decoder.feed(stream.data(), stream.size());
    ASSERT_EQ(frames.size(), 1u) << (byte_by_byte ? "byte by byte" : "at once");
    ASSERT_TRUE(parseStateFrame(frames[0]));
    EXPECT_EQ(parseStateFrame(frames[0])->sequence, 42);
    EXPECT_EQ(decoder.falseStarts(), 1u);
  }
}

// A false start announcing the maximum length covers a whole good frame, and its CRC matches too.
TEST(MotorProtocol, FalseStartSpanningAWholeGoodFrameWithAMatchingCrcIsOverruled) {
  const auto good = sampleStateBytes(7);
  std::vector<uint8_t> stream = {kStart1, kStart2, 0x7F, static_cast<uint8_t>(kMaxPayload)};
  stream.insert(stream.end(), good.begin(), good.end());
  stream.resize(kHeaderSize + kMaxPayload, 0x33);
  const uint32_t crc = crc32c(&stream[2], 2 + kMaxPayload);
  for (int i = 0; i < 4; ++i) stream.push_back(static_cast<uint8_t>(crc >> (8 * i)));
  StreamDecoder decoder;
  const auto frames = decoder.feed(stream.data(), stream.size());
  ASSERT_EQ(frames.size(), 1u);
  ASSERT_TRUE(parseStateFrame(frames[0]));
  EXPECT_EQ(parseStateFrame(frames[0])->sequence, 7);
}

// A false start announcing more bytes than follow must not hold back a complete good frame behind it.
TEST(MotorProtocol, IncompleteFalseStartDoesNotDelayTheNextFrame) {
  std::vector<uint8_t> stream = {0x11, kStart1, kStart2, 0x81, static_cast<uint8_t>(kMaxPayload)};
  const auto good = sampleStateBytes(9);
  stream.insert(stream.end(), good.begin(), good.end());
  StreamDecoder decoder;
  const auto frames = feedByteByByte(decoder, stream);
  ASSERT_EQ(frames.size(), 1u);
  EXPECT_EQ(parseStateFrame(frames[0])->sequence, 9);
}

TEST(MotorProtocol, OutOfRangeDutyIsNotACommand) {
  EXPECT_TRUE(parseDutyFrame(makeDutyFrame(DutyCommand{1, {kDutyFullScale, -kDutyFullScale}})));
  EXPECT_FALSE(parseDutyFrame(makeDutyFrame(DutyCommand{1, {0, kDutyFullScale + 1}})));
  EXPECT_FALSE(parseDutyFrame(makeDutyFrame(DutyCommand{1, {-kDutyFullScale - 1, 0}})));
}

// 1..4 bit flips and 1..4 random byte replacements of zero-duty frames: none may decode to motion
// (CRC-16 let 7 of 2 M through with this harness; make fuzz-serial runs 2 M).
TEST(MotorProtocol, CorruptedZeroDutyFramesNeverMoveAWheel) {
  const auto result = omni_base::serial_fuzz::runCorruptionBenchmark(300000, 12);
  EXPECT_EQ(result.corrupted_frames, 300000u);
  EXPECT_EQ(result.nonzero_duty, 0u);
  EXPECT_EQ(result.clean_frames_lost, 0u);
}

TEST(MotorProtocol, StreamFuzzInvariantsHold) {
  const auto result = omni_base::serial_fuzz::runStreamFuzz(30000, 7);
  EXPECT_GT(result.embedded_frames, 50000u);
  EXPECT_EQ(result.found_frames, result.embedded_frames);
  EXPECT_EQ(result.extra_frames, 0u);
  for (const auto& v : result.violations) ADD_FAILURE() << v;
}

TEST(MotorProtocol, RoundTripOfEveryFrameType) {
  StreamDecoder decoder;
  const DutyCommand duty{7, {10000, -10000, 1234}};
  auto bytes = encodeFrame(makeDutyFrame(duty));
  auto frames = decoder.feed(bytes.data(), bytes.size());
  ASSERT_EQ(frames.size(), 1u);
  auto parsed = parseDutyFrame(frames[0]);
  ASSERT_TRUE(parsed);
  EXPECT_EQ(parsed->sequence, 7);
  EXPECT_EQ(parsed->duty, duty.duty);

  bytes = encodeFrame(makeEnableFrame(EnableCommand{9, true}));
  frames = decoder.feed(bytes.data(), bytes.size());
  ASSERT_EQ(frames.size(), 1u);
  auto enable = parseEnableFrame(frames[0]);
  ASSERT_TRUE(enable);
  EXPECT_TRUE(enable->enable);
  EXPECT_EQ(enable->sequence, 9);

  bytes = sampleStateBytes(3);
  frames = decoder.feed(bytes.data(), bytes.size());
  ASSERT_EQ(frames.size(), 1u);
  auto state = parseStateFrame(frames[0]);
  ASSERT_TRUE(state);
  EXPECT_EQ(state->sequence, 3);
  EXPECT_EQ(state->status, kStatusEnabled);
  EXPECT_EQ(state->encoder_counts, (std::vector<int32_t>{123456, -42, 2147483647}));
  EXPECT_EQ(state->board_time_ms, 987654321u);
  EXPECT_EQ(decoder.crcErrors(), 0u);
  EXPECT_EQ(decoder.garbageBytes(), 0u);
}

TEST(MotorProtocol, TruncatedFrameWaitsForTheRest) {
  StreamDecoder decoder;
  const auto bytes = sampleStateBytes(1);
  for (std::size_t split = 1; split < bytes.size(); ++split) {
    decoder.reset();
    auto first = decoder.feed(bytes.data(), split);
    EXPECT_TRUE(first.empty()) << "split at " << split;
    auto rest = decoder.feed(bytes.data() + split, bytes.size() - split);
    ASSERT_EQ(rest.size(), 1u) << "split at " << split;
    EXPECT_TRUE(parseStateFrame(rest[0]));
  }
}

TEST(MotorProtocol, BadCrcIsDroppedAndTheNextFrameStillDecodes) {
  StreamDecoder decoder;
  auto bad = sampleStateBytes(1);
  bad[6] ^= 0x10;  // flip a payload bit
  auto good = sampleStateBytes(2);
  bad.insert(bad.end(), good.begin(), good.end());
  auto frames = decoder.feed(bad.data(), bad.size());
  ASSERT_EQ(frames.size(), 1u);
  EXPECT_EQ(parseStateFrame(frames[0])->sequence, 2);
  EXPECT_EQ(decoder.crcErrors(), 1u);
}

TEST(MotorProtocol, GarbageBetweenFramesIsSkipped) {
  StreamDecoder decoder;
  std::vector<uint8_t> stream = {0x00, 0xFF, kStart1, 0x13, kStart1, kStart2, 0xEE};  // includes a false start
  auto a = sampleStateBytes(10);
  stream.insert(stream.end(), a.begin(), a.end());
  stream.insert(stream.end(), {0x42, kStart1, 0x99});
  auto b = sampleStateBytes(11);
  stream.insert(stream.end(), b.begin(), b.end());
  // Feed byte by byte: the worst case for a resynchronising decoder.
  std::vector<Frame> frames;
  for (uint8_t byte : stream) {
    auto got = decoder.feed(&byte, 1);
    frames.insert(frames.end(), got.begin(), got.end());
  }
  ASSERT_EQ(frames.size(), 2u);
  EXPECT_EQ(parseStateFrame(frames[0])->sequence, 10);
  EXPECT_EQ(parseStateFrame(frames[1])->sequence, 11);
  EXPECT_GT(decoder.garbageBytes(), 0u);
}

TEST(MotorProtocol, MaximumLengthIsAcceptedAndLongerIsRefused) {
  Frame biggest{0x7F, std::vector<uint8_t>(kMaxPayload, 0xA5)};
  auto bytes = encodeFrame(biggest);
  EXPECT_EQ(bytes.size(), kHeaderSize + kMaxPayload + kCrcSize);
  StreamDecoder decoder;
  auto frames = decoder.feed(bytes.data(), bytes.size());
  ASSERT_EQ(frames.size(), 1u);
  EXPECT_EQ(frames[0].payload.size(), kMaxPayload);

  Frame too_big{0x7F, std::vector<uint8_t>(kMaxPayload + 1, 0)};
  EXPECT_THROW(encodeFrame(too_big), std::invalid_argument);

  // A header announcing more than the maximum is a false start, and what follows still decodes.
  std::vector<uint8_t> stream = {kStart1, kStart2, 0x81, static_cast<uint8_t>(kMaxPayload + 1)};
  auto good = sampleStateBytes(5);
  stream.insert(stream.end(), good.begin(), good.end());
  decoder.reset();
  frames = decoder.feed(stream.data(), stream.size());
  ASSERT_EQ(frames.size(), 1u);
  EXPECT_EQ(parseStateFrame(frames[0])->sequence, 5);
  EXPECT_EQ(decoder.lengthErrors(), 1u);
}

TEST(MotorProtocol, MalformedPayloadsAreNotParsed) {
  EXPECT_FALSE(parseDutyFrame(Frame{0x01, {1, 3, 0, 0}}));        // says 3 wheels, carries 1
  EXPECT_FALSE(parseEnableFrame(Frame{0x02, {1, 2}}));            // enable must be 0 or 1
  EXPECT_FALSE(parseStateFrame(Frame{0x81, {1, 0, 0, 9}}));       // more wheels than the protocol allows
  EXPECT_FALSE(parseStateFrame(Frame{0x01, {}}));                 // wrong type
}
