// libFuzzer target: the CAN IMU decoders (SBG, Bosch MM7, a YAML-style custom decoder with Intel
// and Motorola signals), SocketCAN frame images and error-frame classification, and the DBC bit
// field reader. Input: a sequence of frames, each [flags][id: 4 bytes LE][len][data...].
// Invariants: decoders never crash, emit finite SI values, count every sample they emit, and
// counters never run backwards; bit fields round-trip through insert/extract.

#include <cmath>
#include <cstddef>
#include <cstdint>
#include <cstdlib>
#include <cstring>
#include <span>

#include "drivers/imu/bosch_mm7.hpp"
#include "drivers/imu/can_signal.hpp"
#include "drivers/imu/custom_can.hpp"
#include "drivers/imu/sbg_can.hpp"
#include "drivers/imu/socketcan.hpp"

namespace {

using livod::imu::CanRecord;

livod::imu::CustomCanSpec custom_spec() {
  using livod::imu::ImuAxis;
  using livod::imu::ImuUnit;
  livod::imu::CustomCanSpec s;
  s.signals = {
      {ImuAxis::accel_x, 0x100, {7, 16, true, true}, 0.01, 0.0, ImuUnit::m_s2},
      {ImuAxis::accel_y, 0x100, {23, 12, true, false}, 0.01, -20.0, ImuUnit::m_s2},
      {ImuAxis::accel_z, 0x100, {40, 16, false, true}, 0.0001, 0.0, ImuUnit::g},
      {ImuAxis::gyro_x, 0x18FF0101, {0, 16, false, true}, 0.001, 0.0, ImuUnit::rad_s},
      {ImuAxis::gyro_y, 0x18FF0101, {31, 20, true, true}, 0.01, 0.0, ImuUnit::deg_s},
      {ImuAxis::gyro_z, 0x18FF0101, {48, 16, false, false}, 0.005, -163.84, ImuUnit::deg_s},
  };
  s.sample_id = 0x18FF0101;
  return s;
}

void check(const livod::ImuSample& s) {
  if (!s.accel_m_s2.allFinite() || !s.gyro_rad_s.allFinite()) std::abort();
}

bool monotonic(const livod::imu::ImuDecoderCounters& a, const livod::imu::ImuDecoderCounters& b) {
  return b.frames >= a.frames && b.samples >= a.samples && b.malformed >= a.malformed &&
         b.incomplete >= a.incomplete && b.sequence_gaps >= a.sequence_gaps &&
         b.invalid >= a.invalid;
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  livod::imu::SbgCanDecoder sbg;
  livod::imu::BoschMm7Decoder bosch;
  livod::imu::CustomCanDecoder custom(custom_spec());
  livod::imu::CanImuDecoder* decoders[] = {&sbg, &bosch, &custom};
  std::uint64_t emitted[3] = {0, 0, 0};
  livod::imu::CanBusCounters bus;
  std::size_t pos = 0;
  std::int64_t t = 0;
  while (pos + 6 <= size) {
    const std::uint8_t flags = data[pos];
    std::uint32_t id = 0;
    std::memcpy(&id, data + pos + 1, 4);
    const std::size_t len = std::min<std::size_t>(data[pos + 5], (flags & 1) ? 64 : 8);
    pos += 6;
    const std::size_t n = std::min(len, size - pos);
    CanRecord r;
    r.fd = (flags & 1) != 0;
    r.extended = (flags & 2) != 0;
    r.rtr = (flags & 4) != 0;
    r.error = (flags & 8) != 0;
    // Ids mostly near the decoders' own, so that the fuzzer reaches the decoding paths.
    r.id = (flags & 0x10) ? id & 0x1FFFFFFF : 0x100 + (id & 0x7F);
    r.len = static_cast<std::uint8_t>(n);
    std::memcpy(r.data.data(), data + pos, n);
    r.rx_time_ns = (t += 1000);
    pos += n;
    for (int d = 0; d < 3; ++d) {
      const auto before = decoders[d]->counters();
      decoders[d]->on_frame(r, [&](const livod::ImuSample& s) {
        check(s);
        ++emitted[d];
      });
      if (!monotonic(before, decoders[d]->counters())) std::abort();
    }
    // The socket image of the frame parses back to it.
    const auto image = livod::imu::serialize_can_frame(r);
    CanRecord back;
    if (!livod::imu::parse_can_frame(image, back)) std::abort();
    if (back.error) livod::imu::count_error_frame(back, bus);
    // A bit field taken from the input reads back what was written into it.
    livod::imu::CanBitField f{static_cast<int>(id % 64), static_cast<int>(1 + (id >> 8) % 64),
                              (id & 0x10000) != 0, (id & 0x20000) != 0};
    if (livod::imu::bytes_needed(f)) {
      std::uint8_t buf[8] = {};
      std::memcpy(buf, r.data.data(), 8);
      const std::int64_t v = livod::imu::extract_raw(buf, f);
      std::uint8_t copy[8] = {};
      livod::imu::insert_raw(copy, f, v);
      if (livod::imu::extract_raw(copy, f) != v) std::abort();
    }
  }
  // Arbitrary bytes as a socket frame image.
  CanRecord any;
  (void)livod::imu::parse_can_frame({reinterpret_cast<const std::byte*>(data), size}, any);
  for (int d = 0; d < 3; ++d) {
    if (decoders[d]->counters().samples != emitted[d]) std::abort();
  }
  return 0;
}
