// libFuzzer target: Ouster metadata JSON parsing. Any input must either parse into metadata
// from which a packet format and an XYZ table can be built, or be rejected with livod::Error
// (FormatError for broken JSON, MetadataError for unusable content). Any other exception, crash
// or inconsistency is a bug.

#include <cstddef>
#include <cstdint>
#include <cstdlib>
#include <string_view>

#include "core/error.hpp"
#include "drivers/ouster/metadata.hpp"
#include "drivers/ouster/packet_format.hpp"
#include "drivers/ouster/xyz_lut.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  using namespace livod::drivers::ouster;  // NOLINT: local to the fuzz entry point
  const std::string_view text(reinterpret_cast<const char*>(data), size);
  SensorMetadata m;
  try {
    m = parse_metadata(text, "fuzz");
  } catch (const livod::Error&) {
    return 0;  // rejected cleanly
  }
  const DataFormat& f = m.format;
  if (m.beam_altitude_angles_deg.size() != f.pixels_per_column ||
      m.beam_azimuth_angles_deg.size() != f.pixels_per_column ||
      f.pixel_shift_by_row.size() != f.pixels_per_column || f.columns_per_packet == 0 ||
      f.columns_per_frame % f.columns_per_packet != 0 ||
      f.column_window.first >= f.columns_per_frame || f.column_window.last >= f.columns_per_frame) {
    std::abort();
  }
  const PacketFormat format = PacketFormat::from_metadata(m);
  if (format.lidar_packet_size > 65507 || format.layout == nullptr) std::abort();
  const XyzLut lut(m);
  const Eigen::Vector3f p = lut.point(f.pixels_per_column - 1, f.columns_per_frame - 1, 1000);
  if (!p.allFinite()) std::abort();
  return 0;
}
