#include "drivers/imu/candump_frames.hpp"

#include <algorithm>

namespace livod::imu {

CanRecord to_can_record(const io::CanFrame& f) {
  CanRecord r;
  r.rx_time_ns = f.time_ns;
  r.id = f.id;
  r.extended = f.extended;
  r.fd = f.fd;
  r.rtr = f.rtr;
  r.error = f.error;
  r.len = f.rtr ? 0 : std::min<std::uint8_t>(f.len, 64);
  std::copy_n(f.data.begin(), r.len, r.data.begin());
  return r;
}

io::CanFrame to_candump_frame(const CanRecord& r, const std::string& interface) {
  io::CanFrame f;
  f.time_ns = r.rx_time_ns;
  f.interface = interface;
  f.id = r.id;
  f.extended = r.extended;
  f.fd = r.fd;
  f.rtr = r.rtr;
  f.error = r.error;
  f.len = r.len;
  std::copy_n(r.data.begin(), r.len, f.data.begin());
  return f;
}

}  // namespace livod::imu
