// A raw, non-blocking POSIX serial port (termios), and the pseudo-terminal the fake board offers.
#pragma once

#include <cstddef>
#include <cstdint>
#include <string>
#include <vector>

namespace omni_base {

class SerialPort {
 public:
  SerialPort() = default;
  ~SerialPort();
  SerialPort(const SerialPort&) = delete;
  SerialPort& operator=(const SerialPort&) = delete;

  /// Opens `device` raw (8N1, no flow control) at `baud`. Returns false and sets lastError() on failure.
  bool open(const std::string& device, int baud);
  void close();
  bool isOpen() const { return fd_ >= 0; }

  /// Appends whatever bytes are waiting to `out`. Returns false when the port failed or hung up
  /// (the device was unplugged): the caller should close and reconnect.
  bool readAvailable(std::vector<uint8_t>& out);
  /// Writes all bytes; false on error (see lastError()).
  bool write(const std::vector<uint8_t>& bytes);

  const std::string& lastError() const { return last_error_; }
  const std::string& device() const { return device_; }

  /// termios speed constant for a baud rate, or 0 when the rate is not supported.
  static unsigned int baudConstant(int baud);

 private:
  int fd_{-1};
  std::string device_;
  std::string last_error_;
};

/// The master side of a pseudo-terminal, with a symlink at a fixed path to its slave device so the
/// driver can open "the board" by a stable name. Used by the fake motor board.
class PseudoTerminal {
 public:
  PseudoTerminal() = default;
  ~PseudoTerminal();
  PseudoTerminal(const PseudoTerminal&) = delete;
  PseudoTerminal& operator=(const PseudoTerminal&) = delete;

  /// Creates the pty and the symlink `link_path` -> slave device. False and lastError() on failure.
  bool open(const std::string& link_path);
  /// Closes the pty and removes the symlink: to the driver it looks like an unplugged cable.
  void close();
  bool isOpen() const { return master_fd_ >= 0; }
  int masterFd() const { return master_fd_; }
  const std::string& slavePath() const { return slave_path_; }
  const std::string& lastError() const { return last_error_; }

  bool readAvailable(std::vector<uint8_t>& out);
  bool write(const std::vector<uint8_t>& bytes);

 private:
  int master_fd_{-1};
  int slave_keepalive_fd_{-1};  // keeps the slave open so reads do not fail between driver connections
  std::string link_path_;
  std::string slave_path_;
  std::string last_error_;
};

}  // namespace omni_base
