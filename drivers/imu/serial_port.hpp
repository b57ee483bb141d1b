#pragma once
// The byte transports of serial IMUs (sensor-protocols.md 7.2):
//   SerialPort  a tty (USB-serial adapter, UART, the MTi's own usb-serial driver) in raw mode
//               through termios: 8N1, no flow control, the configured baud rate, non-blocking
//               reads after poll(). For FTDI adapters it lowers the driver's latency timer
//               (16 ms by default, which would quantise receive stamps in 16 ms steps) to 1 ms
//               when it may, and reports what it found.
//   UsbBulkPort a native USB device read with libusb bulk-IN transfers (a vendor USB IMU without
//               a kernel tty driver, or with it detached): device selected by vendor id, product
//               id and optionally serial number.
// Both stamp each read with CLOCK_MONOTONIC when it returns; the protocol's own sample clock is
// what the clock domain fits, the read stamps are its receive times.
//
// A vanished device (POLLHUP, EIO, ENXIO, LIBUSB_ERROR_NO_DEVICE) is reported as a loss; the
// owner closes the port and opens it again later (DeviceThread). Opening a missing device throws
// livod::Error naming it.

#include <cstddef>
#include <cstdint>
#include <memory>
#include <optional>
#include <span>
#include <string>

namespace livod::imu {

struct ByteReadResult {
  enum class Status : std::uint8_t { kData, kIdle, kLost } status = Status::kIdle;
  std::size_t bytes = 0;
  std::int64_t rx_time_ns = 0;  // CLOCK_MONOTONIC when the read returned
};

// A path of the form "usb:VVVV:PPPP[:SERIAL]" (hex ids) selects a native USB device.
struct UsbDeviceSelector {
  std::uint16_t vendor_id = 0;
  std::uint16_t product_id = 0;
  std::string serial;  // empty: the first matching device
};
// nullopt when `path` does not start with "usb:"; throws livod::Error when it does but is
// malformed.
std::optional<UsbDeviceSelector> parse_usb_selector(const std::string& path);

// Baud rates termios can set on Linux (the standard ones); false otherwise.
bool is_supported_baud_rate(int baud);

class BytePort {
 public:
  virtual ~BytePort() = default;
  virtual ByteReadResult read(std::span<std::byte> buffer, int timeout_ms) = 0;
  [[nodiscard]] virtual std::string describe() const = 0;
  [[nodiscard]] virtual std::string loss_reason() const = 0;
};

class SerialPort final : public BytePort {
 public:
  // Opens and configures the tty; throws livod::Error naming the path on failure.
  SerialPort(const std::string& path, int baud_rate);
  ~SerialPort() override;
  SerialPort(const SerialPort&) = delete;
  SerialPort& operator=(const SerialPort&) = delete;

  ByteReadResult read(std::span<std::byte> buffer, int timeout_ms) override;
  [[nodiscard]] std::string describe() const override { return "serial port " + path_; }
  [[nodiscard]] std::string loss_reason() const override { return loss_reason_; }
  // FTDI latency timer after open (ms), when the device has one.
  [[nodiscard]] std::optional<int> latency_timer_ms() const { return latency_timer_ms_; }

 private:
  std::string path_;
  int fd_ = -1;
  std::optional<int> latency_timer_ms_;
  std::string loss_reason_;
};

class UsbBulkPort final : public BytePort {
 public:
  // Finds, opens and claims the device (detaching a kernel driver); throws livod::Error naming
  // the selector on failure.
  explicit UsbBulkPort(const UsbDeviceSelector& selector);
  ~UsbBulkPort() override;
  UsbBulkPort(const UsbBulkPort&) = delete;
  UsbBulkPort& operator=(const UsbBulkPort&) = delete;

  ByteReadResult read(std::span<std::byte> buffer, int timeout_ms) override;
  [[nodiscard]] std::string describe() const override;
  [[nodiscard]] std::string loss_reason() const override { return loss_reason_; }

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
  std::string loss_reason_;
};

}  // namespace livod::imu
