#include "omni_base/serial_port.h"

#include <cerrno>
#include <cstring>
#include <fcntl.h>
#include <poll.h>
#include <termios.h>
#include <unistd.h>

namespace omni_base {
namespace {

std::string errnoText(const std::string& what) { return what + ": " + std::strerror(errno); }

bool makeRaw(int fd, unsigned int speed, std::string& error) {
  termios tio{};
  if (tcgetattr(fd, &tio) != 0) {
    error = errnoText("tcgetattr");
    return false;
  }
  cfmakeraw(&tio);
  tio.c_cflag |= (CLOCAL | CREAD);
  tio.c_cflag &= ~static_cast<tcflag_t>(CRTSCTS | CSTOPB | PARENB);
  tio.c_cc[VMIN] = 0;
  tio.c_cc[VTIME] = 0;
  if (speed != 0 && (cfsetispeed(&tio, speed) != 0 || cfsetospeed(&tio, speed) != 0)) {
    error = errnoText("cfsetspeed");
    return false;
  }
  if (tcsetattr(fd, TCSANOW, &tio) != 0) {
    error = errnoText("tcsetattr");
    return false;
  }
  return true;
}

// Reads what is waiting. Returns false on a hang-up or error. A raw tty with VMIN = VTIME = 0 reads 0
// bytes when nothing is waiting, so a hang-up is told by poll(), not by read() returning 0.
bool drain(int fd, std::vector<uint8_t>& out, std::string& error) {
  uint8_t chunk[512];
  while (true) {
    pollfd pfd{fd, POLLIN, 0};
    if (::poll(&pfd, 1, 0) < 0) {
      if (errno == EINTR) continue;
      error = errnoText("poll");
      return false;
    }
    if (pfd.revents & (POLLERR | POLLNVAL)) {
      error = "device error";
      return false;
    }
    if (!(pfd.revents & POLLIN)) {
      if (pfd.revents & POLLHUP) {
        error = "device hung up (unplugged?)";
        return false;
      }
      return true;  // nothing waiting
    }
    const ssize_t n = ::read(fd, chunk, sizeof(chunk));
    if (n > 0) {
      out.insert(out.end(), chunk, chunk + n);
      continue;
    }
    if (n == 0) return true;
    if (errno == EAGAIN || errno == EWOULDBLOCK) return true;
    if (errno == EINTR) continue;
    error = errnoText("read");
    return false;
  }
}

bool writeAll(int fd, const std::vector<uint8_t>& bytes, std::string& error) {
  std::size_t done = 0;
  int retries = 0;
  while (done < bytes.size()) {
    const ssize_t n = ::write(fd, bytes.data() + done, bytes.size() - done);
    if (n > 0) {
      done += static_cast<std::size_t>(n);
      continue;
    }
    if (n < 0 && errno == EINTR) continue;
    if (n < 0 && (errno == EAGAIN || errno == EWOULDBLOCK) && ++retries < 100) {
      usleep(100);
      continue;
    }
    error = errnoText("write");
    return false;
  }
  return true;
}

}  // namespace

SerialPort::~SerialPort() { close(); }

unsigned int SerialPort::baudConstant(int baud) {
  switch (baud) {
    case 9600: return B9600;
    case 19200: return B19200;
    case 38400: return B38400;
    case 57600: return B57600;
    case 115200: return B115200;
    case 230400: return B230400;
    case 460800: return B460800;
    case 921600: return B921600;
    default: return 0;
  }
}

bool SerialPort::open(const std::string& device, int baud) {
  close();
  device_ = device;
  const unsigned int speed = baudConstant(baud);
  if (speed == 0) {
    last_error_ = "unsupported baud rate " + std::to_string(baud);
    return false;
  }
  fd_ = ::open(device.c_str(), O_RDWR | O_NOCTTY | O_NONBLOCK | O_CLOEXEC);
  if (fd_ < 0) {
    last_error_ = errnoText("cannot open " + device);
    return false;
  }
  if (!makeRaw(fd_, speed, last_error_)) {
    last_error_ = device + ": " + last_error_;
    close();
    return false;
  }
  tcflush(fd_, TCIOFLUSH);
  last_error_.clear();
  return true;
}

void SerialPort::close() {
  if (fd_ >= 0) ::close(fd_);
  fd_ = -1;
}

bool SerialPort::readAvailable(std::vector<uint8_t>& out) {
  if (fd_ < 0) return false;
  if (!drain(fd_, out, last_error_)) {
    last_error_ = device_ + ": " + last_error_;
    return false;
  }
  return true;
}

bool SerialPort::write(const std::vector<uint8_t>& bytes) {
  if (fd_ < 0) return false;
  if (!writeAll(fd_, bytes, last_error_)) {
    last_error_ = device_ + ": " + last_error_;
    return false;
  }
  return true;
}

PseudoTerminal::~PseudoTerminal() { close(); }

bool PseudoTerminal::open(const std::string& link_path) {
  close();
  link_path_ = link_path;
  master_fd_ = posix_openpt(O_RDWR | O_NOCTTY);
  if (master_fd_ < 0 || grantpt(master_fd_) != 0 || unlockpt(master_fd_) != 0) {
    last_error_ = errnoText("cannot create a pseudo-terminal");
    close();
    return false;
  }
  const char* name = ptsname(master_fd_);
  if (name == nullptr) {
    last_error_ = errnoText("ptsname");
    close();
    return false;
  }
  slave_path_ = name;
  fcntl(master_fd_, F_SETFL, fcntl(master_fd_, F_GETFL) | O_NONBLOCK);
  // Raw mode on the slave before anyone talks: a cooked, echoing tty would bounce our frames back.
  slave_keepalive_fd_ = ::open(slave_path_.c_str(), O_RDWR | O_NOCTTY | O_NONBLOCK | O_CLOEXEC);
  if (slave_keepalive_fd_ < 0 || !makeRaw(slave_keepalive_fd_, 0, last_error_)) {
    last_error_ = "cannot configure " + slave_path_ + ": " + last_error_;
    close();
    return false;
  }
  ::unlink(link_path_.c_str());
  if (::symlink(slave_path_.c_str(), link_path_.c_str()) != 0) {
    last_error_ = errnoText("cannot create the link " + link_path_);
    close();
    return false;
  }
  return true;
}

void PseudoTerminal::close() {
  if (!link_path_.empty()) ::unlink(link_path_.c_str());
  if (slave_keepalive_fd_ >= 0) ::close(slave_keepalive_fd_);
  if (master_fd_ >= 0) ::close(master_fd_);
  slave_keepalive_fd_ = -1;
  master_fd_ = -1;
}

bool PseudoTerminal::readAvailable(std::vector<uint8_t>& out) {
  if (master_fd_ < 0) return false;
  return drain(master_fd_, out, last_error_);
}

bool PseudoTerminal::write(const std::vector<uint8_t>& bytes) {
  if (master_fd_ < 0) return false;
  return writeAll(master_fd_, bytes, last_error_);
}

}  // namespace omni_base
