#include "drivers/imu/serial_port.hpp"

#include <fcntl.h>
#include <poll.h>
#include <sys/ioctl.h>
#include <termios.h>
#include <unistd.h>

#include <array>
#include <cerrno>
#include <cstring>
#include <filesystem>
#include <fstream>

#include "core/error.hpp"
#include "core/time.hpp"

namespace livod::imu {
namespace {

struct BaudEntry {
  int baud;
  speed_t code;
};

constexpr std::array<BaudEntry, 16> kBaudRates{{{9600, B9600},
                                                {19200, B19200},
                                                {38400, B38400},
                                                {57600, B57600},
                                                {115200, B115200},
                                                {230400, B230400},
                                                {460800, B460800},
                                                {500000, B500000},
                                                {576000, B576000},
                                                {921600, B921600},
                                                {1000000, B1000000},
                                                {1152000, B1152000},
                                                {1500000, B1500000},
                                                {2000000, B2000000},
                                                {3000000, B3000000},
                                                {4000000, B4000000}}};

std::optional<speed_t> baud_code(int baud) {
  for (const auto& e : kBaudRates) {
    if (e.baud == baud) return e.code;
  }
  return std::nullopt;
}

std::uint16_t parse_hex16(const std::string& text, const std::string& path) {
  if (text.empty() || text.size() > 4)
    throw Error("USB device '" + path + "': bad id '" + text + "'");
  std::uint32_t v = 0;
  for (const char c : text) {
    v <<= 4;
    if (c >= '0' && c <= '9')
      v |= static_cast<std::uint32_t>(c - '0');
    else if (c >= 'a' && c <= 'f')
      v |= static_cast<std::uint32_t>(c - 'a' + 10);
    else if (c >= 'A' && c <= 'F')
      v |= static_cast<std::uint32_t>(c - 'A' + 10);
    else
      throw Error("USB device '" + path + "': bad hex id '" + text + "'");
  }
  return static_cast<std::uint16_t>(v);
}

// FTDI adapters: /sys/bus/usb-serial/devices/ttyUSBn/latency_timer (ms). Lowered to 1 ms when
// writable (root or a udev rule); returns the value in effect.
std::optional<int> tune_latency_timer(const std::string& tty_path) {
  std::error_code ec;
  const auto real = std::filesystem::canonical(tty_path, ec);
  if (ec) return std::nullopt;
  const auto attr =
      std::filesystem::path("/sys/bus/usb-serial/devices") / real.filename() / "latency_timer";
  int value = 0;
  {
    std::ifstream in(attr);
    if (!(in >> value)) return std::nullopt;
  }
  if (value > 1) {
    std::ofstream out(attr);
    out << 1;
    out.flush();
    if (out) value = 1;
  }
  return value;
}

}  // namespace

bool is_supported_baud_rate(int baud) {
  return baud_code(baud).has_value();
}

std::optional<UsbDeviceSelector> parse_usb_selector(const std::string& path) {
  constexpr std::string_view kPrefix = "usb:";
  if (path.rfind(kPrefix, 0) != 0) return std::nullopt;
  const std::string rest = path.substr(kPrefix.size());
  const auto c1 = rest.find(':');
  if (c1 == std::string::npos) {
    throw Error("USB device '" + path +
                "': expected usb:VVVV:PPPP[:SERIAL] (hex vendor and product id)");
  }
  const auto c2 = rest.find(':', c1 + 1);
  UsbDeviceSelector s;
  s.vendor_id = parse_hex16(rest.substr(0, c1), path);
  s.product_id = parse_hex16(
      rest.substr(c1 + 1, c2 == std::string::npos ? std::string::npos : c2 - c1 - 1), path);
  if (c2 != std::string::npos) s.serial = rest.substr(c2 + 1);
  return s;
}

SerialPort::SerialPort(const std::string& path, int baud_rate) : path_(path) {
  const auto code = baud_code(baud_rate);
  if (!code)
    throw Error("serial port " + path + ": unsupported baud rate " + std::to_string(baud_rate));
  fd_ = ::open(path.c_str(), O_RDWR | O_NOCTTY | O_NONBLOCK | O_CLOEXEC);
  if (fd_ < 0) {
    const int err = errno;
    throw Error("serial port " + path + (err == ENOENT ? " does not exist" : " cannot be opened") +
                " (" + std::strerror(err) + ")");
  }
  termios tio{};
  if (::tcgetattr(fd_, &tio) != 0) {
    const int err = errno;
    ::close(fd_);
    throw Error("serial port " + path + " is not a terminal (" + std::strerror(err) + ")");
  }
  ::cfmakeraw(&tio);
  tio.c_cflag |= CLOCAL | CREAD;
  tio.c_cflag &= ~static_cast<tcflag_t>(CSTOPB | CRTSCTS | PARENB);
  tio.c_cflag = (tio.c_cflag & ~static_cast<tcflag_t>(CSIZE)) | CS8;
  tio.c_iflag &= ~static_cast<tcflag_t>(IXON | IXOFF | IXANY);
  tio.c_cc[VMIN] = 0;
  tio.c_cc[VTIME] = 0;
  ::cfsetispeed(&tio, *code);
  ::cfsetospeed(&tio, *code);
  if (::tcsetattr(fd_, TCSANOW, &tio) != 0) {
    const int err = errno;
    ::close(fd_);
    throw Error("serial port " + path + ": cannot configure " + std::to_string(baud_rate) +
                " baud raw mode (" + std::strerror(err) + ")");
  }
  ::tcflush(fd_, TCIFLUSH);  // stale bytes from before the open
  latency_timer_ms_ = tune_latency_timer(path);
}

SerialPort::~SerialPort() {
  if (fd_ >= 0) ::close(fd_);
}

ByteReadResult SerialPort::read(std::span<std::byte> buffer, int timeout_ms) {
  ByteReadResult r;
  pollfd pfd{fd_, POLLIN, 0};
  const int ready = ::poll(&pfd, 1, timeout_ms);
  if (ready <= 0) return r;
  if ((pfd.revents & POLLIN) == 0 && (pfd.revents & (POLLHUP | POLLERR | POLLNVAL)) != 0) {
    loss_reason_ = "serial port " + path_ + ": hang-up (device unplugged?)";
    r.status = ByteReadResult::Status::kLost;
    return r;
  }
  const ssize_t n = ::read(fd_, buffer.data(), buffer.size());
  const int err = errno;
  r.rx_time_ns = host_now().ns;
  if (n > 0) {
    r.status = ByteReadResult::Status::kData;
    r.bytes = static_cast<std::size_t>(n);
    return r;
  }
  if (n < 0 && (err == EAGAIN || err == EINTR)) return r;
  if (n == 0 && (pfd.revents & POLLHUP) == 0) return r;
  loss_reason_ =
      "serial port " + path_ + ": " + (n == 0 ? std::string("end of file") : std::strerror(err));
  r.status = ByteReadResult::Status::kLost;
  return r;
}

}  // namespace livod::imu
