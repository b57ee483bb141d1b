// libFuzzer target: recorded LiDAR messages -> scans (daemon/replay/cloud_conversion.hpp), the
// parser behind every bag replay of PointCloud2 and Livox CustomMsg topics. Byte 0 picks the
// message type and the dataset settings (time unit, reference, stamp convention), the rest is the
// serialized message. A message that decodes must convert or be rejected with a livod::Error;
// every scan must be consistent: all per-point arrays of one length, offsets within the scan, a
// non-empty scan when the call says so.

#include <cstddef>
#include <cstdint>
#include <cstdlib>
#include <span>
#include <vector>

#include "core/error.hpp"
#include "daemon/replay/cloud_conversion.hpp"

namespace {

namespace rb = livod::io::rosbag;
using livod::daemon::DatasetConfig;

void check(const livod::LidarScan& scan, bool emitted) {
  const std::size_t n = scan.size();
  if (emitted != (n > 0)) std::abort();
  if (scan.y.size() != n || scan.z.size() != n || scan.intensity.size() != n ||
      scan.ring.size() != n || scan.return_index.size() != n || scan.t_offset_ns.size() != n ||
      scan.valid.size() != n) {
    std::abort();
  }
  for (const auto t : scan.t_offset_ns) {
    if (t < 0) std::abort();  // offsets count from the scan's first point
  }
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  if (size == 0) return 0;
  const std::uint8_t selector = data[0];
  const std::span<const std::byte> bytes(reinterpret_cast<const std::byte*>(data) + 1, size - 1);
  livod::LidarScan scan;
  livod::daemon::replay::CloudConversionStats stats;
  try {
    if ((selector & 1U) == 0) {
      rb::livox_ros_driver::CustomMsg msg;
      rb::deserialize(bytes, msg);
      check(scan, livod::daemon::replay::custom_msg_to_scan(msg, scan, stats));
    } else {
      rb::sensor_msgs::PointCloud2 msg;
      rb::deserialize(bytes, msg);
      DatasetConfig d;
      constexpr livod::daemon::TimeUnit kUnits[] = {
          livod::daemon::TimeUnit::ns, livod::daemon::TimeUnit::us, livod::daemon::TimeUnit::ms,
          livod::daemon::TimeUnit::s};
      d.time_unit = kUnits[(selector >> 1) & 3U];
      d.time_reference = (selector & 8U) != 0 ? livod::daemon::TimeReference::absolute
                                               : livod::daemon::TimeReference::relative;
      d.stamp = (selector & 16U) != 0 ? livod::daemon::ScanStamp::end
                                       : livod::daemon::ScanStamp::start;
      // The time field: the cloud's last field (so that fuzzed clouds have one), or none found.
      d.time_field = msg.fields.empty() ? "t" : msg.fields.back().name;
      std::vector<rb::CloudPoint> scratch;
      check(scan, livod::daemon::replay::point_cloud_to_scan(msg, d, scratch, scan, stats));
    }
  } catch (const livod::Error&) {
    // Rejected with a reason (FormatError derives from Error): fine.
  }
  return 0;
}
