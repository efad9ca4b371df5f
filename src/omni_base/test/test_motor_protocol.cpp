#include <gtest/gtest.h>

#include "omni_base/motor_protocol.h"

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
}  // namespace

TEST(MotorProtocol, CrcMatchesTheCcittFalseCheckValue) {
  const std::string check = "123456789";
  EXPECT_EQ(crc16(reinterpret_cast<const uint8_t*>(check.data()), check.size()), 0x29B1);
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
