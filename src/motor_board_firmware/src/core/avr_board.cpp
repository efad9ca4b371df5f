#include "motor_board_firmware/avr_board.h"

#include <avr_extint.h>
#include <avr_ioport.h>
#include <avr_uart.h>
#include <sim_avr.h>
#include <sim_hex.h>
#include <sim_irq.h>

#include <cstdarg>
#include <cstdio>
#include <stdexcept>

#include "board_config.h"

namespace motor_board_firmware {
namespace {

#define MBF_LETTER_(x) (#x[0])
#define MBF_LETTER(x) MBF_LETTER_(x)

/// Where simavr's messages for a board go (simavr has one process-wide logger).
struct LogSink {
  std::vector<std::string> lines;
};

void logToBoard(avr_t* avr, const int level, const char* format, va_list args) {
  if (avr == nullptr || level > LOG_WARNING || avr->custom.data == nullptr) return;
  char text[256];
  std::vsnprintf(text, sizeof text, format, args);
  static_cast<LogSink*>(avr->custom.data)->lines.emplace_back(text);
}

/// The harness paces simulated time itself: simavr must not sleep to follow the wall clock.
void noWallClockSleep(avr_t*, avr_cycle_count_t) {}

}  // namespace

// simavr calls back with the avr_t only: its custom.data (unused after avr_init) points at the log sink,
// and the reset hook finds its board here (one board per process at a time).
static AvrBoard* g_board_of_reset = nullptr;

AvrBoard::AvrBoard(const std::string& hex_path) {
  if (g_board_of_reset != nullptr) throw std::logic_error("one AvrBoard per process at a time");
  avr_global_logger_set(&logToBoard);
  avr_ = avr_make_mcu_by_name("atmega328p");
  if (avr_ == nullptr) throw std::runtime_error("simavr has no atmega328p core");
  avr_init(avr_);
  avr_->custom.data = new LogSink();
  avr_->frequency = kCpuHz;
  avr_->sleep = &noWallClockSleep;
  avr_->log = LOG_WARNING;
  ihex_chunk_p chunks = nullptr;
  const int count = read_ihex_chunks(hex_path.c_str(), &chunks);
  if (count <= 0) {
    avr_terminate(avr_);
    throw std::runtime_error("cannot read the firmware image " + hex_path + " (build it: make firmware)");
  }
  for (int i = 0; i < count; ++i) avr_loadcode(avr_, chunks[i].data, chunks[i].size, chunks[i].baseaddr);
  free_ihex_chunks(chunks);
  avr_->codeend = avr_->flashend;

  // INT0 and INT1 (unused by the firmware; their pins carry the enable line and motor 2's PWM) default
  // to low-level sensing, which simavr would poll on every cycle while those pins are low: 2/3 of its time.
  avr_extint_set_strict_lvl_trig(avr_, 0, 0);
  avr_extint_set_strict_lvl_trig(avr_, 1, 0);
  uint32_t no_console = 0;  // simavr would print the UART's lines on stdout
  avr_ioctl(avr_, AVR_IOCTL_UART_SET_FLAGS('0'), &no_console);
  uart_input_ = avr_io_getirq(avr_, AVR_IOCTL_UART_GETIRQ('0'), UART_IRQ_INPUT);
  avr_irq_register_notify(avr_io_getirq(avr_, AVR_IOCTL_UART_GETIRQ('0'), UART_IRQ_OUTPUT), &AvrBoard::onUartOutput, this);
  avr_irq_register_notify(portIrq(MBF_LETTER(BUSY_PORT_LETTER), BUSY_BIT), &AvrBoard::onBusyPin, this);
  core_reset_ = avr_->reset;
  avr_->reset = &AvrBoard::onReset;
  g_board_of_reset = this;
  for (auto& slot : slots_) slot.board = this;
}

AvrBoard::~AvrBoard() {
  delete static_cast<LogSink*>(avr_->custom.data);
  avr_->custom.data = nullptr;
  if (g_board_of_reset == this) g_board_of_reset = nullptr;
  avr_terminate(avr_);
  free(avr_);
}

void AvrBoard::onReset(avr_t* avr) {
  AvrBoard* board = g_board_of_reset;
  if (board != nullptr && board->avr_ == avr) {
    if (board->reset_requested_) {
      ++board->requested_resets_;
    } else {
      ++board->unexpected_resets_;
    }
    board->reset_requested_ = false;
    board->busy_ = false;
    if (board->core_reset_ != nullptr) board->core_reset_(avr);
    board->rearmAfterReset();
  }
}

void AvrBoard::rearmAfterReset() {
  // A reset clears simavr's cycle timers: the line and the harness's own schedule go on.
  for (auto& slot : slots_) {
    if (slot.fn && slot.next_cycle != 0) {
      avr_cycle_timer_register(avr_, slot.next_cycle > avr_->cycle ? slot.next_cycle - avr_->cycle : 1,
                               &AvrBoard::runSlot, &slot);
    }
  }
  if (!rx_queue_.empty()) avr_cycle_timer_register(avr_, byteCycles(), &AvrBoard::feedNextByte, this);
  // A reset clears the PIN registers too, but the pins the harness drives keep their levels.
  for (const auto& [pin, level] : driven_pins_) {
    const uint16_t pin_register = pin.first == 'B' ? reg::kPinB : pin.first == 'C' ? reg::kPinC : reg::kPinD;
    if (level) avr_->data[pin_register] |= static_cast<uint8_t>(1u << pin.second);
  }
}

uint64_t AvrBoard::cycle() const { return avr_->cycle; }

void AvrBoard::runUntil(uint64_t target) {
  while (avr_->cycle < target) {
    const int state = avr_run(avr_);
    if (state == cpu_Done || state == cpu_Crashed) {
      throw std::runtime_error("the firmware stopped at cycle " + std::to_string(avr_->cycle) +
                               (state == cpu_Done ? " (it slept with interrupts off)" : " (crashed)"));
    }
  }
}

uint64_t AvrBoard::byteCycles() const {
  const uint32_t ubrr = avr_->data[reg::kUbrr0L] | (static_cast<uint32_t>(avr_->data[reg::kUbrr0H]) << 8);
  const bool double_speed = (avr_->data[reg::kUcsr0A] & 0x02u) != 0;  // U2X0
  return static_cast<uint64_t>(ubrr + 1) * (double_speed ? 8u : 16u) * 11u;
}

void AvrBoard::sendToBoard(const uint8_t* data, std::size_t size) {
  const bool line_idle = rx_queue_.empty();
  rx_queue_.insert(rx_queue_.end(), data, data + size);
  if (line_idle && !rx_queue_.empty()) avr_cycle_timer_register(avr_, 1, &AvrBoard::feedNextByte, this);
}

uint64_t AvrBoard::feedNextByte(avr_t* avr, uint64_t when, void* param) {
  auto* board = static_cast<AvrBoard*>(param);
  if (board->rx_queue_.empty()) return 0;
  avr_raise_irq(board->uart_input_, board->rx_queue_.front());
  if (board->on_deliver_) board->on_deliver_(TxByte{when, board->rx_queue_.front()});
  board->rx_queue_.pop_front();
  (void)avr;
  return board->rx_queue_.empty() ? 0 : when + board->byteCycles();
}

void AvrBoard::onUartOutput(avr_irq_t*, uint32_t value, void* param) {
  auto* board = static_cast<AvrBoard*>(param);
  const TxByte byte{board->avr_->cycle, static_cast<uint8_t>(value)};
  board->tx_.push_back(byte);
  if (board->on_transmit_) board->on_transmit_(byte);
}

std::vector<TxByte> AvrBoard::takeFromBoard() {
  std::vector<TxByte> out;
  out.swap(tx_);
  return out;
}

void AvrBoard::onBusyPin(avr_irq_t*, uint32_t value, void* param) {
  auto* board = static_cast<AvrBoard*>(param);
  const bool high = (value & 1u) != 0;
  if (high && !board->busy_) {
    board->busy_since_ = board->avr_->cycle;
  } else if (!high && board->busy_) {
    const uint64_t length = board->avr_->cycle - board->busy_since_;
    if (length > board->worst_busy_cycles_) board->worst_busy_cycles_ = length;
    ++board->busy_periods_;
  }
  board->busy_ = high;
}

void AvrBoard::resetBusyStatistics() {
  worst_busy_cycles_ = 0;
  busy_periods_ = 0;
}

avr_irq_t* AvrBoard::portIrq(char port, int bit) const {
  avr_irq_t* irq = avr_io_getirq(avr_, AVR_IOCTL_IOPORT_GETIRQ(port), bit);
  if (irq == nullptr) throw std::runtime_error(std::string("no pin ") + port + std::to_string(bit));
  return irq;
}

void AvrBoard::setPin(char port, int bit, bool level) {
  // Driven from outside (push-pull): the firmware's pull-up must not pull the pin's level with it.
  ExternalDrive& drive = external_drive_[port];
  drive.mask = static_cast<uint8_t>(drive.mask | (1u << bit));
  drive.value = static_cast<uint8_t>(level ? drive.value | (1u << bit) : drive.value & ~(1u << bit));
  avr_ioport_external_t external{};
  external.name = port;
  external.mask = drive.mask;
  external.value = drive.value;
  avr_ioctl(avr_, AVR_IOCTL_IOPORT_SET_EXTERNAL(port), &external);
  avr_raise_irq(portIrq(port, bit), level ? 1 : 0);
  driven_pins_[{port, bit}] = level;
}

void AvrBoard::watchPin(char port, int bit, std::function<void(bool)> callback) {
  pin_watches_.push_back(std::move(callback));
  avr_irq_register_notify(portIrq(port, bit), &AvrBoard::onWatchedPin, &pin_watches_.back());
}

void AvrBoard::onWatchedPin(avr_irq_t*, uint32_t value, void* param) {
  (*static_cast<std::function<void(bool)>*>(param))((value & 1u) != 0);
}

uint8_t AvrBoard::readData(uint16_t address) const { return avr_->data[address]; }
const uint8_t* AvrBoard::data() const { return avr_->data; }

void AvrBoard::pressReset() {
  reset_requested_ = true;
  avr_reset(avr_);
}

void AvrBoard::schedule(uint64_t at_cycle, std::function<uint64_t(uint64_t)> fn, int slot) {
  if (slot < 0 || slot >= kSlots) throw std::out_of_range("AvrBoard::schedule: no slot " + std::to_string(slot));
  slots_[slot].fn = std::move(fn);
  slots_[slot].next_cycle = at_cycle;
  const uint64_t now = avr_->cycle;
  avr_cycle_timer_register(avr_, at_cycle > now ? at_cycle - now : 1, &AvrBoard::runSlot, &slots_[slot]);
}

uint64_t AvrBoard::runSlot(avr_t*, uint64_t when, void* param) {
  auto* slot = static_cast<Slot*>(param);
  slot->next_cycle = slot->fn ? slot->fn(when) : 0;
  return slot->next_cycle;
}

std::vector<std::string> AvrBoard::takeLog() {
  auto* sink = static_cast<LogSink*>(avr_->custom.data);
  std::vector<std::string> out;
  out.swap(sink->lines);
  return out;
}

}  // namespace motor_board_firmware
