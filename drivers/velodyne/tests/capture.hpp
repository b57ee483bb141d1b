#pragma once
// Test helper: runs every UDP datagram of a capture through a decoder and keeps the results.

#include <filesystem>
#include <vector>

#include "core/measurement.hpp"
#include "drivers/lidar_decoder.hpp"
#include "io/pcap.hpp"

namespace livod::drivers::velodyne::capture {

struct Decoded {
  std::vector<LidarScan> scans;
  std::vector<ImuSample> imu;
};

// Decodes the whole capture (flushing the last scan); payloads can be modified on the way by
// `edit` (return false to drop the datagram).
template <class Edit>
Decoded decode_capture(const std::filesystem::path& capture, LidarDecoder& decoder, Edit edit) {
  Decoded out;
  DecoderSinks sinks;
  sinks.on_scan = [&out](const LidarScan& scan) { out.scans.push_back(scan); };
  sinks.on_imu = [&out](const ImuSample& sample) { out.imu.push_back(sample); };
  io::PcapReader reader(capture);
  std::vector<std::byte> buffer;
  while (auto datagram = reader.next()) {
    buffer.assign(datagram->payload.begin(), datagram->payload.end());
    if (!edit(buffer, *datagram)) continue;
    decoder.on_packet(PacketView{buffer, datagram->capture_time_ns, datagram->dst_port}, sinks);
  }
  decoder.flush(sinks);
  return out;
}

inline Decoded decode_capture(const std::filesystem::path& capture, LidarDecoder& decoder) {
  return decode_capture(capture, decoder,
                        [](std::vector<std::byte>&, io::UdpDatagram&) { return true; });
}

}  // namespace livod::drivers::velodyne::capture
