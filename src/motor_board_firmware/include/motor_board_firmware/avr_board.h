// The motor board's MCU in simavr (ROS-free): an ATmega328P at 16 MHz running the firmware's .hex, with
// its UART fed at the line's byte rate, its pins readable and drivable, its resets counted and its
// main loop timed on the busy pin. Everything runs in simulated time (CPU cycles); the caller decides
// how that relates to the wall clock.
#pragma once

#include <cstdint>
#include <deque>
#include <functional>
#include <list>
#include <map>
#include <string>
#include <vector>

struct avr_t;
struct avr_irq_t;

namespace motor_board_firmware {

constexpr uint32_t kCpuHz = 16000000u;

/// ATmega328P data-space addresses of the registers the harness reads (datasheet, "Register Summary").
namespace reg {
constexpr uint16_t kPinB = 0x23, kDdrB = 0x24, kPortB = 0x25;
constexpr uint16_t kPinC = 0x26, kDdrC = 0x27, kPortC = 0x28;
constexpr uint16_t kPinD = 0x29, kDdrD = 0x2A, kPortD = 0x2B;
constexpr uint16_t kTccr0A = 0x44, kTccr0B = 0x45, kOcr0A = 0x47, kOcr0B = 0x48;
constexpr uint16_t kTccr2A = 0xB0, kTccr2B = 0xB1, kOcr2A = 0xB3, kOcr2B = 0xB4;
constexpr uint16_t kUcsr0A = 0xC0, kUbrr0L = 0xC4, kUbrr0H = 0xC5;
constexpr uint16_t kRamStart = 0x100, kRamEnd = 0x8FF;
}  // namespace reg

/// A byte on the line and its cycle: written by the firmware to its UART, or delivered to it.
struct TxByte {
  uint64_t cycle;
  uint8_t value;
};

class AvrBoard {
 public:
  /// Loads the Intel HEX image; throws std::runtime_error when it cannot.
  explicit AvrBoard(const std::string& hex_path);
  ~AvrBoard();
  AvrBoard(const AvrBoard&) = delete;
  AvrBoard& operator=(const AvrBoard&) = delete;

  uint64_t cycle() const;
  double seconds() const { return static_cast<double>(cycle()) / kCpuHz; }
  /// Runs the CPU until `cycle` (at most one instruction past it). Throws if the firmware crashed
  /// (an invalid instruction or jump, or it slept with interrupts off).
  void runUntil(uint64_t cycle);

  /// Bytes on their way from the host: they enter the UART one byte time apart, from now on.
  void sendToBoard(const uint8_t* data, std::size_t size);
  std::size_t bytesWaitingForTheLine() const { return rx_queue_.size(); }
  /// Called for each host byte as it enters the UART, with its cycle (optional).
  void onDeliver(std::function<void(const TxByte&)> callback) { on_deliver_ = std::move(callback); }
  /// Cycles one byte takes on the line at the UART's current baud setting (simavr counts 11 bit
  /// times per byte: start, 8 data, a parity slot, stop).
  uint64_t byteCycles() const;
  /// Takes what the firmware transmitted since the last call.
  std::vector<TxByte> takeFromBoard();
  /// Called for each byte the firmware transmits, at the cycle it does (optional).
  void onTransmit(std::function<void(const TxByte&)> callback) { on_transmit_ = std::move(callback); }

  /// Drives an input pin (port 'B', 'C' or 'D').
  void setPin(char port, int bit, bool level);
  /// Calls `callback(level)` whenever the level of a pin changes (however briefly).
  void watchPin(char port, int bit, std::function<void(bool)> callback);
  uint8_t readData(uint16_t address) const;
  const uint8_t* data() const;

  /// The reset button (a power cycle's effect on the MCU: registers cleared, the firmware restarts).
  void pressReset();
  /// Resets the firmware did not ask the harness for: the hardware watchdog, a crash to the reset vector.
  uint64_t unexpectedResets() const { return unexpected_resets_; }
  uint64_t requestedResets() const { return requested_resets_; }

  /// The main loop's time per cycle: busy pin high to low, in CPU cycles.
  uint64_t worstBusyCycles() const { return worst_busy_cycles_; }
  uint64_t busyPeriods() const { return busy_periods_; }
  void resetBusyStatistics();

  /// Schedules fn at an absolute cycle (simavr cycle timer); fn returns the next cycle to run at, or 0.
  void schedule(uint64_t at_cycle, std::function<uint64_t(uint64_t)> fn, int slot);

  /// simavr's warnings and errors since the last call (e.g. a UART receive overrun).
  std::vector<std::string> takeLog();

 private:
  static void onUartOutput(avr_irq_t* irq, uint32_t value, void* param);
  static void onBusyPin(avr_irq_t* irq, uint32_t value, void* param);
  static uint64_t feedNextByte(avr_t* avr, uint64_t when, void* param);
  static uint64_t runSlot(avr_t* avr, uint64_t when, void* param);
  static void onReset(avr_t* avr);
  void rearmAfterReset();
  avr_irq_t* portIrq(char port, int bit) const;

  avr_t* avr_{nullptr};
  void (*core_reset_)(avr_t*){nullptr};
  avr_irq_t* uart_input_{nullptr};
  std::deque<uint8_t> rx_queue_;
  std::vector<TxByte> tx_;
  std::function<void(const TxByte&)> on_transmit_;
  std::function<void(const TxByte&)> on_deliver_;
  std::map<std::pair<char, int>, bool> driven_pins_;
  struct ExternalDrive {
    uint8_t mask{0};
    uint8_t value{0};
  };
  std::map<char, ExternalDrive> external_drive_;
  std::list<std::function<void(bool)>> pin_watches_;
  static void onWatchedPin(avr_irq_t* irq, uint32_t value, void* param);
  bool reset_requested_{false};
  uint64_t unexpected_resets_{0};
  uint64_t requested_resets_{0};
  uint64_t busy_since_{0};
  bool busy_{false};
  uint64_t worst_busy_cycles_{0};
  uint64_t busy_periods_{0};
  static constexpr int kSlots = 6;
  struct Slot {
    AvrBoard* board{nullptr};
    std::function<uint64_t(uint64_t)> fn;
    uint64_t next_cycle{0};
  };
  Slot slots_[kSlots];
};

}  // namespace motor_board_firmware
