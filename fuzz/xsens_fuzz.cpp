// libFuzzer target: the Xsens MTData2 stream decoder. The input is split into reads at sizes taken
// from its first bytes (messages torn anywhere); the same bytes fed whole must give the same
// samples. Samples are finite, counters monotonic, every emitted sample counted.

#include <cstddef>
#include <cstdint>
#include <cstdlib>
#include <span>
#include <vector>

#include "drivers/imu/xsens_mtdata2.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  if (size < 2) return 0;
  const std::size_t chunk = 1 + data[0] % 64;
  const std::span<const std::byte> bytes(reinterpret_cast<const std::byte*>(data + 1), size - 1);

  livod::imu::XsensMtData2Decoder whole;
  std::vector<livod::ImuSample> a;
  whole.on_bytes(bytes, 1, [&](const livod::ImuSample& s) { a.push_back(s); });

  livod::imu::XsensMtData2Decoder torn;
  std::vector<livod::ImuSample> b;
  for (std::size_t i = 0; i < bytes.size(); i += chunk) {
    const auto before = torn.counters();
    torn.on_bytes(bytes.subspan(i, std::min(chunk, bytes.size() - i)), 1,
                  [&](const livod::ImuSample& s) { b.push_back(s); });
    const auto& c = torn.counters();
    if (c.bytes < before.bytes || c.samples < before.samples ||
        c.checksum_errors < before.checksum_errors || c.skipped_bytes < before.skipped_bytes) {
      std::abort();
    }
  }
  if (a.size() != b.size() || whole.counters().samples != a.size()) std::abort();
  for (std::size_t i = 0; i < a.size(); ++i) {
    if (!a[i].accel_m_s2.allFinite() || !a[i].gyro_rad_s.allFinite()) std::abort();
    if (a[i].accel_m_s2 != b[i].accel_m_s2 || a[i].stamp.sensor != b[i].stamp.sensor) std::abort();
  }
  return 0;
}
