// The firmware in the loop (ROS-free): the MCU (AvrBoard) with its three motor channels read every
// model step, the wheels (WheelMotor) or an outside plant behind them, and quadrature edges on the
// encoder pins. Also what the tests measure: when valid commands reached the board, when the drive
// stopped, and whether a motor pin was ever driven high.
#pragma once

#include <array>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "motor_board_firmware/avr_board.h"
#include "motor_board_firmware/motor_plant.h"
#include "omni_base/motor_protocol.h"

namespace motor_board_firmware {

struct BoardBenchConfig {
  std::string hex_path;
  WheelMotorConfig motor;
  double counts_per_rev{1320.0};
  double model_step_s{1e-4};
  /// true: the wheels are this bench's WheelMotors. false: an outside plant (the docking simulator)
  /// turns them and reports counts through setEncoderTargets().
  bool internal_plant{true};
};

/// The firmware's section sizes and the RAM addresses the harness looks at (where the painted free RAM
/// starts, __heap_start; the encoder glitch counter): read from the .elf.
struct FirmwareImage {
  uint32_t text_bytes{0};
  uint32_t data_bytes{0};
  uint32_t bss_bytes{0};
  uint32_t noinit_bytes{0};
  uint16_t heap_start{0};
  uint16_t encoder_glitches{0};  ///< address of the firmware's encoder_glitches (data space)
  uint32_t flashBytes() const { return text_bytes + data_bytes; }
  uint32_t staticRamBytes() const { return data_bytes + bss_bytes + noinit_bytes; }
};
/// Drives one encoder's A/B pins: moves toward a target count one Gray-code edge at a time, the edges
/// spread evenly over a window.
class QuadratureOutput {
 public:
  QuadratureOutput(AvrBoard& board, char port, int bit_a, int bit_b, int slot);
  void moveTo(int64_t count, uint64_t over_cycles);
  int64_t emitted() const { return emitted_; }

 private:
  uint64_t emitEdge(uint64_t now);

  AvrBoard& board_;
  char port_;
  int bit_a_, bit_b_, slot_;
  int64_t emitted_{0};
  int64_t target_{0};
  uint64_t spacing_{0};
  uint64_t last_edge_cycle_{0};
};

class BoardBench {
 public:
  explicit BoardBench(const BoardBenchConfig& config);

  AvrBoard& board() { return *board_; }
  double seconds() const { return board_->seconds(); }
  /// Runs the simulation to `seconds` of simulated time.
  void runUntil(double seconds);
  void runFor(double seconds) { runUntil(board_->seconds() + seconds); }

  /// Host bytes onto the line; the frames the board sent since the last call, decoded by the host's codec.
  void send(const std::vector<uint8_t>& bytes) { board_->sendToBoard(bytes.data(), bytes.size()); }
  std::vector<omni_base::protocol::BoardState> receiveStates();
  /// Raw bytes the board sent since the last call (instead of receiveStates()).
  std::vector<uint8_t> receiveBytes();

  const MotorOutputs& outputs() const { return outputs_; }
  double wheelSpeed(std::size_t i) const { return motors_[i].speed(); }
  double wheelAngle(std::size_t i) const { return motors_[i].angle(); }
  const WheelMotor& motor(std::size_t i) const { return motors_[i]; }
  int64_t encoderEdges(std::size_t i) const { return encoders_[i]->emitted(); }
  /// Outside plant: its counts, played back as edges over the next window.
  void setEncoderTargets(const std::vector<int64_t>& counts, double window_s);

  /// When (s) the last valid command (ENABLE or SET_DUTY the board accepts) finished arriving, if any.
  std::optional<double> lastValidCommandAt() const { return last_valid_command_s_; }
  /// When (s) the drive last went from some motor driven to none (every duty zero or the bridges off).
  std::optional<double> lastDriveStopAt() const { return last_drive_stop_s_; }
  /// Model steps with a non-zero duty on enabled bridges, and motor pins (PWM or enable) seen high at
  /// any instant (simavr raises them however briefly they are driven).
  uint64_t drivenSteps() const { return driven_steps_; }
  uint64_t pwmPinHighEvents() const { return pwm_pin_high_events_; }
  uint64_t enablePinHighEvents() const { return enable_pin_high_events_; }
  uint64_t misconfiguredSteps() const { return misconfigured_steps_; }

  /// Peak stack in bytes: free RAM the firmware painted at start-up and has overwritten since.
  std::size_t peakStackBytes() const;
  /// The firmware's count of encoder transitions with both channels changed (an edge it missed).
  uint16_t firmwareEncoderGlitches() const;

 private:
  uint64_t modelStep(uint64_t now);
  void watchHostBytes(const TxByte& byte);
  void watchMotorPins();

  BoardBenchConfig config_;
  std::unique_ptr<AvrBoard> board_;
  std::vector<WheelMotor> motors_;
  std::array<std::unique_ptr<QuadratureOutput>, kWheels> encoders_;
  uint64_t step_cycles_;
  MotorOutputs outputs_;
  bool driving_{false};
  omni_base::protocol::StreamDecoder host_stream_;   // what the board is being sent
  omni_base::protocol::StreamDecoder board_stream_;  // what the board sends
  std::vector<uint8_t> board_bytes_;
  std::optional<double> last_valid_command_s_;
  std::optional<double> last_drive_stop_s_;
  uint64_t driven_steps_{0};
  uint64_t pwm_pin_high_events_{0};
  uint64_t enable_pin_high_events_{0};
  uint64_t misconfigured_steps_{0};
  FirmwareImage image_;
};

FirmwareImage readFirmwareImage(const std::string& elf_path);

/// The firmware's build outputs (the .hex the board runs, the .elf beside it), as built by this
/// workspace; overridable with MOTOR_BOARD_FIRMWARE_DIR in the environment.
std::string firmwareHexPath();
std::string firmwareElfPath();

}  // namespace motor_board_firmware
