// The motor board's firmware on the simulated ATmega328P (libsimavr), against the host's own protocol
// codec: start-up state, the protocol's rules, PWM and encoder counting in the loop with the motor
// model, the command watchdog, garbage and floods, a reset mid-drive, and the memory and time budgets.
// Deterministic: simulated time only, fixed seeds.
#include <gtest/gtest.h>
#include <yaml-cpp/yaml.h>

#include <chrono>
#include <cmath>
#include <cstdio>
#include <random>

#include "board_config.h"
#include "motor_board_firmware/board_bench.h"
#include "omni_base/motor_protocol.h"

using namespace motor_board_firmware;
namespace protocol = omni_base::protocol;

namespace {

const YAML::Node& baseConfig() {
  static const YAML::Node node = YAML::LoadFile(OMNI_BASE_CONFIG);
  return node;
}

BoardBenchConfig benchConfig() {
  BoardBenchConfig c;
  c.hex_path = firmwareHexPath();
  c.motor.volts_per_rad_s = baseConfig()["motor"]["volts_per_rad_s"].as<double>();
  c.motor.supply_volts = baseConfig()["motor"]["supply_volts"].as<double>();
  c.motor.time_constant_s = baseConfig()["motor"]["time_constant_s"].as<double>();
  c.counts_per_rev = baseConfig()["wheels"]["encoder_counts_per_rev"].as<double>();
  return c;
}

std::vector<uint8_t> enableFrame(uint8_t sequence, bool enable) {
  return protocol::encodeFrame(protocol::makeEnableFrame({sequence, enable}));
}

std::vector<uint8_t> dutyFrame(uint8_t sequence, std::vector<int16_t> duty) {
  return protocol::encodeFrame(protocol::makeDutyFrame({sequence, std::move(duty)}));
}

/// Sends SET_DUTY every 20 ms (the host's 50 Hz) for `seconds`; returns the last sequence used.
uint8_t holdDuty(BoardBench& bench, const std::vector<int16_t>& duty, double seconds, uint8_t sequence) {
  const double end = bench.seconds() + seconds;
  while (bench.seconds() < end - 1e-9) {
    bench.send(dutyFrame(sequence++, duty));
    bench.runFor(0.02);
  }
  return sequence;
}

/// Steady speed of a host duty after the firmware's 8-bit PWM quantisation.
double quantizedSteadySpeed(const BoardBench& bench, std::size_t wheel, int16_t duty) {
  const double steps = std::round(std::abs(duty) * 256.0 / 10000.0);
  return bench.motor(wheel).steadySpeed(std::copysign(steps / 256.0, duty));
}

std::vector<uint8_t> randomBytes(std::size_t n, uint32_t seed) {
  std::mt19937 rng(seed);
  std::vector<uint8_t> out(n);
  for (auto& b : out) b = static_cast<uint8_t>(rng());
  return out;
}

/// Runs until every queued host byte is on the line, plus `settle` seconds.
void drain(BoardBench& bench, double settle) {
  while (bench.board().bytesWaitingForTheLine() > 0) bench.runFor(0.01);
  bench.runFor(settle);
}

}  // namespace

TEST(Firmware, StartsWithTheBridgesOffAndSaysNothing) {
  BoardBench bench(benchConfig());
  bench.runFor(0.3);
  EXPECT_FALSE(bench.outputs().bridges_enabled);
  for (double d : bench.outputs().duty) EXPECT_EQ(d, 0.0);
  EXPECT_EQ(bench.drivenSteps(), 0u);
  EXPECT_EQ(bench.pwmPinHighEvents(), 0u);
  EXPECT_EQ(bench.enablePinHighEvents(), 0u);
  EXPECT_TRUE(bench.receiveBytes().empty());
  EXPECT_EQ(bench.board().unexpectedResets(), 0u);
  // Every motor pin an output driven low (not floating on the pull-downs alone).
  const uint8_t motor_pins_d = (1u << 6) | (1u << 5) | (1u << 3) | (1u << 4) | (1u << 7) | (1u << 2);
  EXPECT_EQ(bench.board().readData(reg::kDdrD) & motor_pins_d, motor_pins_d);
  EXPECT_EQ(bench.board().readData(reg::kPortD) & motor_pins_d, 0);
  EXPECT_EQ(bench.board().readData(reg::kDdrB) & 1u, 1u);
  EXPECT_EQ(bench.board().readData(reg::kPortB) & 1u, 0u);
}

TEST(Firmware, AnswersEachValidCommandOnceAndIgnoresTheRest) {
  BoardBench bench(benchConfig());
  bench.runFor(0.01);
  protocol::BoardState echo;
  echo.encoder_counts = {1, 2, 3};
  bench.send(protocol::encodeFrame(protocol::makeStateFrame(echo)));   // its own kind of frame
  bench.send(protocol::encodeFrame({0x03, {1, 1}}));                   // unknown type
  bench.send(dutyFrame(1, {100, 100}));                                // wrong wheel count
  bench.send(protocol::encodeFrame({MP_TYPE_SET_DUTY, {2, 3, 0x11, 0x27, 0, 0, 0, 0}}));  // duty 10001
  bench.send(protocol::encodeFrame({MP_TYPE_ENABLE, {3, 2}}));          // enable 2
  auto enable = enableFrame(4, true);
  enable[5] ^= 0x01;                                                   // a bad CRC
  bench.send(enable);
  drain(bench, 0.05);
  EXPECT_TRUE(bench.receiveStates().empty());
  EXPECT_EQ(bench.drivenSteps(), 0u);

  bench.send(enableFrame(7, true));
  drain(bench, 0.01);
  auto states = bench.receiveStates();
  ASSERT_EQ(states.size(), 1u);
  EXPECT_EQ(states[0].sequence, 7);
  EXPECT_EQ(states[0].status, protocol::kStatusEnabled);
  EXPECT_EQ(states[0].faults, 0);
  EXPECT_EQ(states[0].encoder_counts.size(), 3u);
  ASSERT_TRUE(bench.lastValidCommandAt());
  // Latched when the frame arrived; the board clock starts after the start-up code (< 1 ms).
  EXPECT_NEAR(states[0].board_time_ms, *bench.lastValidCommandAt() * 1000.0, 2.0);

  bench.send(dutyFrame(8, {0, 0, 0}));
  bench.send(enableFrame(9, false));
  drain(bench, 0.01);
  states = bench.receiveStates();
  ASSERT_EQ(states.size(), 2u);
  EXPECT_EQ(states[0].sequence, 8);
  EXPECT_EQ(states[1].sequence, 9);
  EXPECT_EQ(states[1].status, 0);
}

TEST(Firmware, DutiesTurnTheWheelsAndEveryEdgeIsCounted) {
  BoardBench bench(benchConfig());
  bench.runFor(0.01);
  bench.send(enableFrame(0, true));
  const std::vector<int16_t> duty = {3000, -5000, 8000};
  uint8_t sequence = holdDuty(bench, duty, 1.0, 1);
  for (std::size_t i = 0; i < kWheels; ++i) {
    const double expected = quantizedSteadySpeed(bench, i, duty[i]);
    EXPECT_NEAR(bench.wheelSpeed(i), expected, 1e-3 * std::abs(expected)) << "wheel " << i;
    EXPECT_NEAR(bench.outputs().duty[i], duty[i] / 10000.0, 0.5 / 256.0) << "wheel " << i;
  }
  holdDuty(bench, {0, 0, 0}, 0.5, sequence);
  bench.receiveStates();
  bench.send(enableFrame(200, true));
  drain(bench, 0.01);
  const auto states = bench.receiveStates();
  ASSERT_EQ(states.size(), 1u);
  for (std::size_t i = 0; i < kWheels; ++i) {
    EXPECT_EQ(bench.wheelSpeed(i), 0.0) << "wheel " << i;
    EXPECT_EQ(states[0].encoder_counts[i], bench.encoderEdges(i)) << "wheel " << i;
    EXPECT_GT(std::abs(bench.encoderEdges(i)), 1000) << "wheel " << i;
    EXPECT_EQ(bench.encoderEdges(i) > 0, duty[i] > 0) << "wheel " << i;
  }
  EXPECT_EQ(bench.firmwareEncoderGlitches(), 0u);
}

TEST(Firmware, CommandWatchdogStopsTheMotorsWithinItsTimeout) {
  BoardBench bench(benchConfig());
  bench.runFor(0.01);
  bench.send(enableFrame(0, true));
  holdDuty(bench, {4000, 4000, -4000}, 0.5, 1);
  ASSERT_TRUE(bench.outputs().bridges_enabled);
  bench.runFor(0.6);  // the host went quiet
  ASSERT_TRUE(bench.lastValidCommandAt() && bench.lastDriveStopAt());
  const double stop_s = *bench.lastDriveStopAt() - *bench.lastValidCommandAt();
  std::printf("[ FIGURE   ] board watchdog: drive stopped %.4f s (simulated) after the last valid command\n", stop_s);
  EXPECT_LE(stop_s, MP_BOARD_WATCHDOG_MS / 1000.0 + 1e-4);  // one model step of sampling
  EXPECT_GE(stop_s, MP_BOARD_WATCHDOG_MS / 1000.0 - 2e-3);
  for (double d : bench.outputs().duty) EXPECT_EQ(d, 0.0);
  for (std::size_t i = 0; i < kWheels; ++i) EXPECT_EQ(bench.wheelSpeed(i), 0.0);
  // The next command is answered with the watchdog's stop cleared, and drives again.
  bench.receiveStates();
  holdDuty(bench, {4000, 0, 0}, 0.1, 50);
  EXPECT_GT(bench.outputs().duty[0], 0.0);
}

TEST(Firmware, AMillionRandomBytesNeitherMoveAWheelNorResetTheBoard) {
  BoardBench bench(benchConfig());
  bench.runFor(0.01);
  const auto wall_start = std::chrono::steady_clock::now();
  const auto garbage = randomBytes(1000000, 58);
  bench.send(garbage);
  bench.board().resetBusyStatistics();
  drain(bench, 0.05);
  const double wall_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - wall_start).count();
  std::printf("[ FIGURE   ] 1 M random bytes over %.1f s of line (simulated, %.1f s wall): %llu firmware resets, "
              "%llu steps with a non-zero duty, %llu PWM pin and %llu enable pin high events, %zu reply bytes, "
              "worst main-loop cycle %llu CPU cycles\n",
              bench.seconds(), wall_s, static_cast<unsigned long long>(bench.board().unexpectedResets()),
              static_cast<unsigned long long>(bench.drivenSteps()),
              static_cast<unsigned long long>(bench.pwmPinHighEvents()),
              static_cast<unsigned long long>(bench.enablePinHighEvents()), bench.receiveBytes().size(),
              static_cast<unsigned long long>(bench.board().worstBusyCycles()));
  EXPECT_EQ(bench.board().unexpectedResets(), 0u);
  EXPECT_EQ(bench.drivenSteps(), 0u);
  EXPECT_EQ(bench.pwmPinHighEvents(), 0u);
  EXPECT_EQ(bench.enablePinHighEvents(), 0u);
  // Still listening: a valid command after the garbage is answered.
  bench.send(enableFrame(1, false));
  drain(bench, 0.01);
  EXPECT_EQ(bench.receiveStates().size(), 1u);
}

TEST(Firmware, FloodsAndCorruptedFramesNeverMoveAWheelNorHangTheBoard) {
  BoardBench bench(benchConfig());
  bench.runFor(0.01);
  bench.send(enableFrame(0, true));  // bridges on at zero duty: only a decoded non-zero duty could move a wheel
  drain(bench, 0.01);
  // 1. Back-to-back valid commands for 2 s: each answer (28 bytes) is longer than its command (16),
  //    so answers are dropped, never waited for.
  std::vector<uint8_t> flood;
  for (int i = 0; i < 1400; ++i) {
    const auto f = dutyFrame(static_cast<uint8_t>(i), {0, 0, 0});
    flood.insert(flood.end(), f.begin(), f.end());
  }
  // 2. 20 000 zero-duty frames with 1..4 flipped bits, each followed by an intact one.
  std::mt19937 rng(58);
  for (int i = 0; i < 20000; ++i) {
    auto f = dutyFrame(static_cast<uint8_t>(i), {0, 0, 0});
    const auto intact = f;
    const int flips = 1 + static_cast<int>(rng() % 4);
    for (int k = 0; k < flips; ++k) f[rng() % f.size()] ^= static_cast<uint8_t>(1u << (rng() % 8));
    flood.insert(flood.end(), f.begin(), f.end());
    flood.insert(flood.end(), intact.begin(), intact.end());
  }
  // 3. False starts back to back, each announcing a 64-byte frame (the decoder's worst case).
  for (int i = 0; i < 4000; ++i) {
    const uint8_t header[4] = {0xA5, 0x5A, 0x01, 0x40};
    flood.insert(flood.end(), header, header + 4);
  }
  bench.send(flood);
  bench.board().resetBusyStatistics();
  drain(bench, 0.05);
  std::printf("[ FIGURE   ] floods (%zu bytes: 2 s of valid commands, 20 000 corrupted frames, 16 000 bytes of false "
              "starts): %llu firmware resets, %llu steps with a non-zero duty, worst main-loop cycle %llu CPU cycles\n",
              flood.size(), static_cast<unsigned long long>(bench.board().unexpectedResets()),
              static_cast<unsigned long long>(bench.drivenSteps()),
              static_cast<unsigned long long>(bench.board().worstBusyCycles()));
  EXPECT_EQ(bench.board().unexpectedResets(), 0u);
  EXPECT_EQ(bench.drivenSteps(), 0u);
  EXPECT_EQ(bench.pwmPinHighEvents(), 0u);
  EXPECT_GT(bench.receiveStates().size(), 20000u);  // the intact frames were answered
  bench.send(enableFrame(1, false));
  drain(bench, 0.01);
  const auto states = bench.receiveStates();
  ASSERT_FALSE(states.empty());
  EXPECT_EQ(states.back().sequence, 1);
}

TEST(Firmware, AResetMidDriveDropsTheDriveAndRestartsTheClockAndCounters) {
  BoardBench bench(benchConfig());
  bench.runFor(0.01);
  bench.send(enableFrame(0, true));
  holdDuty(bench, {6000, 6000, 6000}, 0.5, 1);
  ASSERT_TRUE(bench.outputs().bridges_enabled);
  const double reset_at = bench.seconds();
  std::array<int64_t, kWheels> edges_at_reset{};
  for (std::size_t i = 0; i < kWheels; ++i) edges_at_reset[i] = bench.encoderEdges(i);
  bench.board().pressReset();
  bench.runFor(0.001);
  EXPECT_FALSE(bench.outputs().bridges_enabled);  // the pins float: the pull-downs hold the bridges off
  for (double d : bench.outputs().duty) EXPECT_EQ(d, 0.0);
  bench.runFor(4.0);  // the wheels coast to rest on friction alone
  for (std::size_t i = 0; i < kWheels; ++i) ASSERT_EQ(bench.wheelSpeed(i), 0.0);
  bench.receiveStates();
  bench.send(enableFrame(9, false));
  drain(bench, 0.01);
  const auto states = bench.receiveStates();
  ASSERT_EQ(states.size(), 1u);
  EXPECT_EQ(states[0].status, 0);  // started disabled
  EXPECT_LT(states[0].board_time_ms, (bench.seconds() - reset_at) * 1000.0 + 1.0);
  for (std::size_t i = 0; i < kWheels; ++i) {
    // Edges during the ~1 ms start-up (before the pin-change interrupt is on) are not counted: at the
    // ~12 rad/s of the reset that is 2-3 counts; the host's reboot handling absorbs them.
    const int64_t since_reset = bench.encoderEdges(i) - edges_at_reset[i];
    EXPECT_LE(states[0].encoder_counts[i], since_reset) << "wheel " << i;
    EXPECT_GE(states[0].encoder_counts[i], since_reset - 6) << "wheel " << i;
    EXPECT_GT(states[0].encoder_counts[i], 0) << "wheel " << i;  // it counted the coasting
  }
  EXPECT_EQ(bench.board().requestedResets(), 1u);
  EXPECT_EQ(bench.board().unexpectedResets(), 0u);
}

TEST(Firmware, MemoryAndTimeStayWithinBudget) {
  const FirmwareImage image = readFirmwareImage(firmwareElfPath());
  BoardBench bench(benchConfig());
  bench.runFor(0.01);
  // A workload that reaches every path: drive, reverse, stop, garbage, a flood, the watchdog.
  bench.send(enableFrame(0, true));
  uint8_t sequence = holdDuty(bench, {9000, -9000, 5000}, 0.5, 1);
  sequence = holdDuty(bench, {-9000, 9000, -5000}, 0.5, sequence);
  bench.send(randomBytes(20000, 7));
  drain(bench, 0.3);
  holdDuty(bench, {10000, 10000, 10000}, 0.3, sequence);
  bench.runFor(0.4);
  const std::size_t stack = bench.peakStackBytes();
  const std::size_t ram = image.staticRamBytes() + stack;
  std::printf("[ FIGURE   ] flash %u of 32768 bytes (%.1f %%); RAM data %u + bss %u + noinit %u + peak stack %zu = %zu of "
              "2048 bytes (%.1f %%); worst main-loop cycle in this workload %llu CPU cycles (%.1f us)\n",
              image.flashBytes(), 100.0 * image.flashBytes() / 32768.0, image.data_bytes, image.bss_bytes,
              image.noinit_bytes, stack, ram, 100.0 * ram / 2048.0,
              static_cast<unsigned long long>(bench.board().worstBusyCycles()),
              bench.board().worstBusyCycles() / 16.0);
  EXPECT_LE(image.flashBytes(), 32768u / 2);
  EXPECT_GT(stack, 16u);  // the paint was overwritten: the measurement works
  EXPECT_LE(ram, 2048u * 3 / 4);
  EXPECT_EQ(bench.board().unexpectedResets(), 0u);
  EXPECT_EQ(bench.misconfiguredSteps(), 0u);
}

TEST(Firmware, CountsPerRevolutionAreTheBaseConfigs) {
  EXPECT_EQ(static_cast<double>(ENCODER_COUNTS_PER_WHEEL_REV),
            baseConfig()["wheels"]["encoder_counts_per_rev"].as<double>());
}
