// libFuzzer target: the VectorNav binary output stream decoder. The input is split into reads at
// sizes taken from its first byte (packets torn anywhere); the same bytes fed whole must give the
// same samples. Samples are finite with a non-negative sensor time, counters never run backwards,
// every emitted sample is counted, and no more bytes are skipped than were fed.

#include <cstddef>
#include <cstdint>
#include <cstdlib>
#include <span>
#include <vector>

#include "drivers/imu/vectornav_binary.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  if (size < 2) return 0;
  const std::size_t chunk = 1 + data[0] % 64;
  const std::span<const std::byte> bytes(reinterpret_cast<const std::byte*>(data + 1), size - 1);

  livod::imu::VectorNavBinaryDecoder whole;
  std::vector<livod::ImuSample> a;
  whole.on_bytes(bytes, 1, [&](const livod::ImuSample& s) { a.push_back(s); });

  livod::imu::VectorNavBinaryDecoder torn;
  std::vector<livod::ImuSample> b;
  for (std::size_t i = 0; i < bytes.size(); i += chunk) {
    const auto before = torn.counters();
    torn.on_bytes(bytes.subspan(i, std::min(chunk, bytes.size() - i)), 1,
                  [&](const livod::ImuSample& s) { b.push_back(s); });
    const auto& c = torn.counters();
    if (c.bytes < before.bytes || c.samples < before.samples || c.frames < before.frames ||
        c.checksum_errors < before.checksum_errors || c.malformed < before.malformed ||
        c.skipped_bytes < before.skipped_bytes || c.sequence_gaps < before.sequence_gaps) {
      std::abort();
    }
  }
  const auto& w = whole.counters();
  if (a.size() != b.size() || w.samples != a.size() || w.skipped_bytes > w.bytes) std::abort();
  if (w.frames != torn.counters().frames || w.sequence_gaps != torn.counters().sequence_gaps) {
    std::abort();
  }
  for (std::size_t i = 0; i < a.size(); ++i) {
    if (!a[i].accel_m_s2.allFinite() || !a[i].gyro_rad_s.allFinite()) std::abort();
    if (a[i].stamp.sensor.ns < 0) std::abort();
    if (a[i].accel_m_s2 != b[i].accel_m_s2 || a[i].gyro_rad_s != b[i].gyro_rad_s ||
        a[i].stamp.sensor != b[i].stamp.sensor) {
      std::abort();
    }
  }
  return 0;
}
