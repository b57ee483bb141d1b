// libusb bulk-IN reader for native USB IMUs (serial_port.hpp).

#include <libusb.h>

#include <cstdio>

#include "core/error.hpp"
#include "core/time.hpp"
#include "drivers/imu/serial_port.hpp"

namespace livod::imu {
namespace {

std::string describe_selector(const UsbDeviceSelector& s) {
  char ids[16];
  std::snprintf(ids, sizeof(ids), "%04x:%04x", s.vendor_id, s.product_id);
  return std::string("USB device ") + ids + (s.serial.empty() ? "" : " serial " + s.serial);
}

// The string descriptor `index` of an open device ("" on failure).
std::string string_descriptor(libusb_device_handle* h, std::uint8_t index) {
  if (index == 0) return {};
  unsigned char buf[256];
  const int n = libusb_get_string_descriptor_ascii(h, index, buf, sizeof(buf));
  return n > 0 ? std::string(reinterpret_cast<char*>(buf), static_cast<std::size_t>(n))
               : std::string();
}

}  // namespace

struct UsbBulkPort::Impl {
  UsbDeviceSelector selector;
  libusb_context* ctx = nullptr;
  libusb_device_handle* handle = nullptr;
  int interface = -1;
  unsigned char endpoint = 0;

  ~Impl() {
    if (handle != nullptr) {
      if (interface >= 0) libusb_release_interface(handle, interface);
      libusb_close(handle);
    }
    if (ctx != nullptr) libusb_exit(ctx);
  }
};

UsbBulkPort::UsbBulkPort(const UsbDeviceSelector& selector) : impl_(std::make_unique<Impl>()) {
  impl_->selector = selector;
  const std::string what = describe_selector(selector);
  if (const int rc = libusb_init(&impl_->ctx); rc != 0) {
    impl_->ctx = nullptr;
    throw Error(what + ": libusb_init failed (" + libusb_error_name(rc) + ")");
  }
  libusb_device** list = nullptr;
  const ssize_t n = libusb_get_device_list(impl_->ctx, &list);
  for (ssize_t i = 0; i < n && impl_->handle == nullptr; ++i) {
    libusb_device_descriptor desc{};
    if (libusb_get_device_descriptor(list[i], &desc) != 0) continue;
    if (desc.idVendor != selector.vendor_id || desc.idProduct != selector.product_id) continue;
    libusb_device_handle* h = nullptr;
    if (libusb_open(list[i], &h) != 0) continue;
    if (!selector.serial.empty() && string_descriptor(h, desc.iSerialNumber) != selector.serial) {
      libusb_close(h);
      continue;
    }
    impl_->handle = h;
    // First interface with a bulk IN endpoint.
    libusb_config_descriptor* config = nullptr;
    if (libusb_get_active_config_descriptor(list[i], &config) == 0) {
      for (int f = 0; f < config->bNumInterfaces && impl_->interface < 0; ++f) {
        const auto& alt = config->interface[f].altsetting[0];
        for (int e = 0; e < alt.bNumEndpoints; ++e) {
          const auto& ep = alt.endpoint[e];
          if ((ep.bmAttributes & LIBUSB_TRANSFER_TYPE_MASK) == LIBUSB_TRANSFER_TYPE_BULK &&
              (ep.bEndpointAddress & LIBUSB_ENDPOINT_IN) != 0) {
            impl_->interface = alt.bInterfaceNumber;
            impl_->endpoint = ep.bEndpointAddress;
            break;
          }
        }
      }
      libusb_free_config_descriptor(config);
    }
  }
  if (list != nullptr) libusb_free_device_list(list, 1);
  if (impl_->handle == nullptr) throw Error(what + " not found (is it plugged in? permissions?)");
  if (impl_->interface < 0) throw Error(what + " has no bulk IN endpoint");
  libusb_set_auto_detach_kernel_driver(impl_->handle, 1);
  if (const int rc = libusb_claim_interface(impl_->handle, impl_->interface); rc != 0) {
    const int iface = impl_->interface;
    impl_->interface = -1;
    throw Error(what + ": cannot claim interface " + std::to_string(iface) + " (" +
                libusb_error_name(rc) + ")");
  }
}

UsbBulkPort::~UsbBulkPort() = default;

std::string UsbBulkPort::describe() const {
  return describe_selector(impl_->selector);
}

ByteReadResult UsbBulkPort::read(std::span<std::byte> buffer, int timeout_ms) {
  ByteReadResult r;
  int transferred = 0;
  const int rc = libusb_bulk_transfer(impl_->handle, impl_->endpoint,
                                      reinterpret_cast<unsigned char*>(buffer.data()),
                                      static_cast<int>(buffer.size()), &transferred,
                                      static_cast<unsigned>(timeout_ms > 0 ? timeout_ms : 1));
  r.rx_time_ns = host_now().ns;
  if (transferred > 0) {
    r.status = ByteReadResult::Status::kData;
    r.bytes = static_cast<std::size_t>(transferred);
    return r;
  }
  if (rc == 0 || rc == LIBUSB_ERROR_TIMEOUT || rc == LIBUSB_ERROR_INTERRUPTED ||
      rc == LIBUSB_ERROR_OVERFLOW) {
    return r;
  }
  loss_reason_ = describe() + ": " + libusb_error_name(rc);
  r.status = ByteReadResult::Status::kLost;
  return r;
}

}  // namespace livod::imu
