// Damaged input: truncated, oversized, corrupted and missing packets are counted and skipped,
// never a crash; the packets around them decode as before.

#include <gtest/gtest.h>

#include <random>
#include <vector>

#include "drivers/velodyne/data_packet.hpp"
#include "drivers/velodyne/tests/capture.hpp"
#include "drivers/velodyne/velodyne_decoder.hpp"
#include "tests/support/data_dir.hpp"

namespace livod::drivers::velodyne {
namespace {

const char* const kMonterey = "velodyne/veloview/monterey-first-100-packets.pcap";

VelodyneOptions hdl_options() {
  VelodyneOptions options;
  options.model = Model::kHdl32e;
  return options;
}

std::size_t total_points(const capture::Decoded& d) {
  std::size_t n = 0;
  for (const auto& s : d.scans) n += s.size();
  return n;
}

TEST(Robustness, CorruptedPacketsAreCountedAndSkipped) {
  VelodyneDecoder clean(hdl_options());
  const auto reference = capture::decode_capture(livod::test::data_path(kMonterey), clean);
  ASSERT_EQ(clean.counters().decode_errors, 0U);

  VelodyneDecoder decoder(hdl_options());
  std::size_t data_index = 0;
  std::size_t position_index = 0;
  std::size_t damaged = 0;
  std::size_t damaged_data = 0;
  std::size_t wrong_length = 0;
  std::size_t damaged_returns = 0;
  const auto decoded = capture::decode_capture(
      livod::test::data_path(kMonterey), decoder,
      [&](std::vector<std::byte>& payload, io::UdpDatagram&) {
        if (payload.size() == 512) {
          if (position_index++ % 50 == 7) {  // truncated position packets
            payload.resize(300);
            ++damaged;
            ++wrong_length;
          }
          return true;
        }
        const std::size_t i = data_index++;
        if (i < 100 || i % 97 != 0) return true;
        std::size_t nonzero = 0;
        for (std::size_t k = 0; k < 12 * 32; ++k) {
          const std::size_t at = (k / 32) * 100 + 4 + (k % 32) * 3;
          nonzero += (payload[at] != std::byte{0} || payload[at + 1] != std::byte{0}) ? 1 : 0;
        }
        damaged_returns += nonzero;
        ++damaged;
        ++damaged_data;
        switch ((i / 97) % 5) {
          case 0:
            payload.resize(1205);  // truncated
            ++wrong_length;
            break;
          case 1:
            payload.push_back(std::byte{0});  // oversized
            ++wrong_length;
            break;
          case 2:
            payload[500] = std::byte{0x12};  // block 5 flag: FF EE -> 12 EE
            break;
          case 3:
            payload[702] = std::byte{0x41};  // block 7 azimuth 0x9C41 = 40001 > 36000
            payload[703] = std::byte{0x9C};
            break;
          default:
            payload[1203] = std::byte{0xF0};  // ToH > one hour
            break;
        }
        return true;
      });
  EXPECT_EQ(decoder.counters().decode_errors, damaged);
  EXPECT_EQ(decoder.counters().packets, clean.counters().packets);
  EXPECT_EQ(decoder.counters().lidar_packets + decoder.counters().imu_packets + damaged,
            clean.counters().lidar_packets + clean.counters().imu_packets);
  EXPECT_EQ(decoder.velodyne_counters().bad_length, wrong_length);
  EXPECT_EQ(decoder.velodyne_counters().bad_content, damaged - wrong_length);
  EXPECT_GT(damaged_data, 20U);
  // Every skipped data packet is also a gap in the azimuth sequence.
  EXPECT_EQ(decoder.counters().sequence_gaps, damaged_data);
  EXPECT_EQ(total_points(decoded) + damaged_returns, total_points(reference));
}

TEST(Robustness, MissingPacketsAreSequenceGaps) {
  for (const std::size_t run : {1U, 2U, 5U}) {
    VelodyneDecoder decoder(hdl_options());
    std::size_t data_index = 0;
    std::size_t dropped = 0;
    (void)capture::decode_capture(livod::test::data_path(kMonterey), decoder,
                                  [&](std::vector<std::byte>& payload, io::UdpDatagram&) {
                                    if (payload.size() != 1206) return true;
                                    const std::size_t i = data_index++;
                                    // Runs of missing packets after packets 100, 400, ...
                                    // (a loss at the very end of a capture is invisible).
                                    if (i % 300 >= 100 && i % 300 < 100 + run) {
                                      ++dropped;
                                      return false;
                                    }
                                    return true;
                                  });
    EXPECT_EQ(decoder.counters().sequence_gaps, dropped) << "run " << run;
    EXPECT_GE(decoder.counters().incomplete_scans, dropped / run) << "run " << run;
  }
}

TEST(Robustness, ReorderedPacketIsDroppedAndCountedOnce) {
  VelodyneDecoder decoder(hdl_options());
  std::vector<std::byte> held;
  std::size_t data_index = 0;
  std::size_t scans = 0;
  DecoderSinks sinks;
  sinks.on_scan = [&scans](const LidarScan&) { ++scans; };
  io::PcapReader reader(livod::test::data_path(kMonterey));
  std::vector<std::byte> buffer;
  while (auto d = reader.next()) {
    if (d->payload.size() != 1206) continue;
    buffer.assign(d->payload.begin(), d->payload.end());
    const std::size_t i = data_index++;
    if (i == 500) {  // hold packet 500 back and deliver it after 501
      held = buffer;
      continue;
    }
    decoder.on_packet(PacketView{buffer, d->capture_time_ns, d->dst_port}, sinks);
    if (i == 501) decoder.on_packet(PacketView{held, d->capture_time_ns, d->dst_port}, sinks);
  }
  EXPECT_EQ(decoder.velodyne_counters().late_packets, 1U);
  EXPECT_EQ(decoder.counters().sequence_gaps, 1U);  // 499 -> 501 skipped one packet
  EXPECT_EQ(decoder.counters().decode_errors, 0U);
  // The late packet did not cut a scan: the same 19 scans as without reordering.
  EXPECT_EQ(decoder.counters().scans, 18U);  // the 19th (partial) is still open: no flush here
  EXPECT_EQ(scans, 18U);
}

TEST(Robustness, RandomBytesNeverCrashThePacketDecoders) {
  std::mt19937 rng(12345);
  VelodyneOptions options;
  for (const auto& t : all_models()) {
    options.model = t.model;
    VelodyneDecoder decoder(options);
    DecoderSinks sinks;
    std::size_t emitted = 0;
    sinks.on_scan = [&emitted](const LidarScan& s) { emitted += s.size(); };
    std::vector<std::byte> payload;
    for (int k = 0; k < 3000; ++k) {
      const std::size_t size = (k % 3 == 0) ? 1206 : (k % 3 == 1) ? 512 : rng() % 1400;
      payload.resize(size);
      for (auto& b : payload) b = static_cast<std::byte>(rng());
      // Make a third of the data packets well-formed enough to reach the geometry code.
      if (size == 1206 && k % 2 == 0) {
        for (int blk = 0; blk < 12; ++blk) {
          const std::uint16_t flag =
              t.model == Model::kVls128 ? (0xEEFF - 0x1100 * (blk % 4)) : 0xEEFF;
          payload[static_cast<std::size_t>(blk) * 100] = static_cast<std::byte>(flag & 0xFF);
          payload[static_cast<std::size_t>(blk) * 100 + 1] = static_cast<std::byte>(flag >> 8);
          const auto az = static_cast<std::uint16_t>(rng() % 36001);
          payload[static_cast<std::size_t>(blk) * 100 + 2] = static_cast<std::byte>(az & 0xFF);
          payload[static_cast<std::size_t>(blk) * 100 + 3] = static_cast<std::byte>(az >> 8);
        }
        payload[1203] = std::byte{0};  // ToH < 2^24 us
      }
      decoder.on_packet(PacketView{payload, k * 1'000'000LL, 2368}, sinks);
    }
    decoder.flush(sinks);
    const auto& c = decoder.counters();
    EXPECT_EQ(c.packets, 3000U) << t.name;
    EXPECT_EQ(c.lidar_packets + c.imu_packets + c.aux_packets + c.decode_errors, c.packets)
        << t.name;
    EXPECT_GT(c.lidar_packets, 0U) << t.name;
    EXPECT_EQ(c.points, emitted) << t.name;
  }
}

TEST(Robustness, PureDecoderRejectsShortOutputBuffers) {
  const DataPacketDecoder decoder(Model::kVlp16, default_calibration(Model::kVlp16), {});
  std::vector<std::byte> payload(1206, std::byte{0});
  std::vector<DecodedReturn> small(10);
  EXPECT_EQ(decoder.decode(payload, 0.0, small).status, DataDecodeStatus::kBadLength);
  std::vector<DecodedReturn> enough(DataPacketDecoder::kMaxReturns);
  EXPECT_EQ(decoder.decode(payload, 0.0, enough).status, DataDecodeStatus::kBadBlockFlag);
}

}  // namespace
}  // namespace livod::drivers::velodyne
