#include "motor_board_firmware/board_bench.h"

#include <elf.h>

#include <cmath>
#include <cstdlib>
#include <cstring>
#include <fstream>
#include <iterator>
#include <stdexcept>

#include "board_config.h"

namespace motor_board_firmware {
namespace {

#define MBF_LETTER_(x) (#x[0])
#define MBF_LETTER(x) MBF_LETTER_(x)

constexpr uint8_t kStackPaint = 0xC5;   // firmware/main.c
// 150 us between two edges of one encoder (6 700 edges/s, 1.45x a wheel at full speed: 21.8 rad/s x
// 1320 / 2 pi = 4 580/s, 218 us apart). A backlog (the harness behind the simulator's clock) drains at that
// rate. Closer edges would meet a simavr 1.6 quirk: an interrupt raised while interrupts are off (an atomic
// block) is serviced up to 2 048 cycles (timer 0's period, 128 us) later, and two edges of one encoder in
// that time read as one missed edge (measured: 7 per 20 s run at 50 us spacing, 0 at 150 us).
constexpr uint64_t kMinEdgeSpacing = 2400;

/// Count -> A | B << 1 (forward: A leads B), the firmware's encoders.c convention.
constexpr std::array<int, 4> kGray = {0, 1, 3, 2};

/// The .elf the .hex was made from (the same build), for the harness's look into the firmware's RAM.
std::string elfPathBeside(const std::string& hex_path) {
  const auto dot = hex_path.rfind('.');
  return (dot == std::string::npos ? hex_path : hex_path.substr(0, dot)) + ".elf";
}

}  // namespace

QuadratureOutput::QuadratureOutput(AvrBoard& board, char port, int bit_a, int bit_b, int slot)
    : board_(board), port_(port), bit_a_(bit_a), bit_b_(bit_b), slot_(slot) {
  board_.setPin(port_, bit_a_, false);
  board_.setPin(port_, bit_b_, false);
}

void QuadratureOutput::moveTo(int64_t count, uint64_t over_cycles) {
  target_ = count;
  const uint64_t edges = static_cast<uint64_t>(std::llabs(target_ - emitted_));
  if (edges == 0) return;
  spacing_ = std::max<uint64_t>(kMinEdgeSpacing, over_cycles / edges);
  const uint64_t first = std::max(board_.cycle() + spacing_ / 2 + 1, last_edge_cycle_ + kMinEdgeSpacing);
  board_.schedule(first, [this](uint64_t now) { return emitEdge(now); }, slot_);
}

uint64_t QuadratureOutput::emitEdge(uint64_t now) {
  if (emitted_ == target_) return 0;
  const int before = kGray[static_cast<std::size_t>(emitted_ & 3)];
  emitted_ += target_ > emitted_ ? 1 : -1;
  const int after = kGray[static_cast<std::size_t>(emitted_ & 3)];
  const int changed = before ^ after;  // exactly one channel
  if (changed & 1) board_.setPin(port_, bit_a_, after & 1);
  if (changed & 2) board_.setPin(port_, bit_b_, (after >> 1) & 1);
  last_edge_cycle_ = now;
  return emitted_ == target_ ? 0 : now + spacing_;
}

BoardBench::BoardBench(const BoardBenchConfig& config)
    : config_(config),
      board_(std::make_unique<AvrBoard>(config.hex_path)),
      motors_(kWheels, WheelMotor(config.motor)),
      step_cycles_(static_cast<uint64_t>(std::llround(config.model_step_s * kCpuHz))),
      image_(readFirmwareImage(elfPathBeside(config.hex_path))) {
  const char encoder_port = MBF_LETTER(ENCODER_PORT_LETTER);
  for (std::size_t i = 0; i < kWheels; ++i) {
    encoders_[i] = std::make_unique<QuadratureOutput>(*board_, encoder_port, static_cast<int>(2 * i),
                                                      static_cast<int>(2 * i + 1), static_cast<int>(i));
  }
  board_->onDeliver([this](const TxByte& byte) { watchHostBytes(byte); });
  board_->onTransmit([this](const TxByte& byte) { board_bytes_.push_back(byte.value); });
  watchMotorPins();
  board_->schedule(step_cycles_, [this](uint64_t now) { return modelStep(now); }, static_cast<int>(kWheels));
}

void BoardBench::watchMotorPins() {
  auto pwm_high = [this](bool high) {
    if (high) ++pwm_pin_high_events_;
  };
  board_->watchPin(MBF_LETTER(MOTOR0_PWM_PORT), MOTOR0_PWM_BIT, pwm_high);
  board_->watchPin(MBF_LETTER(MOTOR1_PWM_PORT), MOTOR1_PWM_BIT, pwm_high);
  board_->watchPin(MBF_LETTER(MOTOR2_PWM_PORT), MOTOR2_PWM_BIT, pwm_high);
  board_->watchPin(MBF_LETTER(DRIVER_ENABLE_PORT), DRIVER_ENABLE_BIT, [this](bool high) {
    if (high) ++enable_pin_high_events_;
  });
}

void BoardBench::watchHostBytes(const TxByte& byte) {
  // The host's own codec says which frames the board must accept (the firmware's rules: a SET_DUTY for
  // its wheel count with every duty in range, an ENABLE of 0 or 1).
  for (const auto& frame : host_stream_.feed(&byte.value, 1)) {
    const auto duty = omni_base::protocol::parseDutyFrame(frame);
    if ((duty && duty->duty.size() == kWheels) || omni_base::protocol::parseEnableFrame(frame)) {
      // The frame is whole when its last byte's stop bit is in, one byte time after it started.
      last_valid_command_s_ = static_cast<double>(byte.cycle + board_->byteCycles()) / kCpuHz;
    }
  }
}

uint64_t BoardBench::modelStep(uint64_t now) {
  outputs_ = readMotorOutputs(board_->data());
  if (outputs_.misconfigured) ++misconfigured_steps_;
  bool driving = false;
  for (double d : outputs_.duty) driving = driving || (outputs_.bridges_enabled && d != 0.0);
  if (driving) ++driven_steps_;
  if (driving_ && !driving) last_drive_stop_s_ = static_cast<double>(now) / kCpuHz;
  driving_ = driving;
  if (config_.internal_plant) {
    for (std::size_t i = 0; i < kWheels; ++i) {
      motors_[i].step(outputs_.duty[i], outputs_.bridges_enabled, config_.model_step_s);
      const auto count = static_cast<int64_t>(std::floor(motors_[i].angle() / (2.0 * M_PI) * config_.counts_per_rev));
      if (count != encoders_[i]->emitted()) encoders_[i]->moveTo(count, step_cycles_);
    }
  }
  return now + step_cycles_;
}

void BoardBench::setEncoderTargets(const std::vector<int64_t>& counts, double window_s) {
  const auto window = static_cast<uint64_t>(std::max(0.0, window_s) * kCpuHz);
  for (std::size_t i = 0; i < kWheels && i < counts.size(); ++i) encoders_[i]->moveTo(counts[i], window);
}

void BoardBench::runUntil(double seconds) { board_->runUntil(static_cast<uint64_t>(std::llround(seconds * kCpuHz))); }

std::vector<omni_base::protocol::BoardState> BoardBench::receiveStates() {
  std::vector<omni_base::protocol::BoardState> states;
  for (const auto& frame : board_stream_.feed(board_bytes_.data(), board_bytes_.size())) {
    if (auto state = omni_base::protocol::parseStateFrame(frame)) states.push_back(*state);
  }
  board_bytes_.clear();
  return states;
}

std::vector<uint8_t> BoardBench::receiveBytes() {
  std::vector<uint8_t> out;
  out.swap(board_bytes_);
  return out;
}

std::size_t BoardBench::peakStackBytes() const {
  uint16_t lowest = image_.heap_start;
  while (lowest <= reg::kRamEnd && board_->readData(lowest) == kStackPaint) ++lowest;
  return static_cast<std::size_t>(reg::kRamEnd + 1 - lowest);
}

uint16_t BoardBench::firmwareEncoderGlitches() const {
  return static_cast<uint16_t>(board_->readData(image_.encoder_glitches) |
                               (board_->readData(static_cast<uint16_t>(image_.encoder_glitches + 1)) << 8));
}

FirmwareImage readFirmwareImage(const std::string& elf_path) {
  std::ifstream file(elf_path, std::ios::binary);
  const std::vector<char> bytes((std::istreambuf_iterator<char>(file)), std::istreambuf_iterator<char>());
  if (bytes.size() < sizeof(Elf32_Ehdr) || std::memcmp(bytes.data(), ELFMAG, SELFMAG) != 0) {
    throw std::runtime_error("not an ELF file: " + elf_path);
  }
  Elf32_Ehdr header;
  std::memcpy(&header, bytes.data(), sizeof header);
  auto section = [&](std::size_t i) {
    Elf32_Shdr s;
    std::memcpy(&s, bytes.data() + header.e_shoff + i * header.e_shentsize, sizeof s);
    return s;
  };
  const Elf32_Shdr names = section(header.e_shstrndx);
  FirmwareImage image;
  for (std::size_t i = 0; i < header.e_shnum; ++i) {
    const Elf32_Shdr s = section(i);
    const std::string name(bytes.data() + names.sh_offset + s.sh_name);
    if (name == ".text") image.text_bytes = s.sh_size;
    if (name == ".data") image.data_bytes = s.sh_size;
    if (name == ".bss") image.bss_bytes = s.sh_size;
    if (name == ".noinit") image.noinit_bytes = s.sh_size;
    if (s.sh_type != SHT_SYMTAB) continue;
    const Elf32_Shdr strings = section(s.sh_link);
    for (std::size_t k = 0; k < s.sh_size / sizeof(Elf32_Sym); ++k) {
      Elf32_Sym symbol;
      std::memcpy(&symbol, bytes.data() + s.sh_offset + k * sizeof symbol, sizeof symbol);
      const char* name = bytes.data() + strings.sh_offset + symbol.st_name;
      const auto data_address = static_cast<uint16_t>(symbol.st_value & 0xFFFFu);  // data space is at 0x800000
      if (std::strcmp(name, "__heap_start") == 0) image.heap_start = data_address;
      if (std::strcmp(name, "encoder_glitches") == 0) image.encoder_glitches = data_address;
    }
  }
  if (image.heap_start == 0 || image.encoder_glitches == 0) {
    throw std::runtime_error("no __heap_start or encoder_glitches symbol in " + elf_path);
  }
  return image;
}

std::string firmwareHexPath() {
  const char* dir = std::getenv("MOTOR_BOARD_FIRMWARE_DIR");
  return std::string(dir != nullptr ? dir : MOTOR_BOARD_FIRMWARE_DIR) + "/motor_board.hex";
}

std::string firmwareElfPath() {
  const char* dir = std::getenv("MOTOR_BOARD_FIRMWARE_DIR");
  return std::string(dir != nullptr ? dir : MOTOR_BOARD_FIRMWARE_DIR) + "/motor_board.elf";
}

}  // namespace motor_board_firmware
