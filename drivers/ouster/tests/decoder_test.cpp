// Scan assembly (OusterDecoder) on real captures: frame boundaries, column windows, same-port
// captures with IPv4 fragments, init-id changes, gaps, late packets, per-point times, and no
// allocation in steady state.

#include "drivers/ouster/ouster_decoder.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <atomic>
#include <cmath>
#include <cstdlib>
#include <cstring>
#include <map>
#include <new>
#include <set>

#include "drivers/ouster/ouster_factory.hpp"
#include "drivers/ouster/tests/ouster_test_util.hpp"
#include "tests/support/data_dir.hpp"

// Allocation counter for the steady-state test (replaces the global operator new of this binary).
namespace {
std::atomic<std::uint64_t> g_allocations{0};
}  // namespace

// GCC flags free() of memory from this operator new once it inlines both: they do match here.
#if defined(__GNUC__) && !defined(__clang__)
#pragma GCC diagnostic push
#pragma GCC diagnostic ignored "-Wmismatched-new-delete"
#endif
void* operator new(std::size_t n) {
  g_allocations.fetch_add(1, std::memory_order_relaxed);
  if (void* p = std::malloc(n == 0 ? 1 : n)) return p;
  throw std::bad_alloc();
}
void operator delete(void* p) noexcept {
  std::free(p);
}
void operator delete(void* p, std::size_t) noexcept {
  std::free(p);
}
#if defined(__GNUC__) && !defined(__clang__)
#pragma GCC diagnostic pop
#endif

namespace livod::drivers::ouster {
namespace {

using testutil::CapturedPacket;
using testutil::ipv4;
using testutil::read_capture;

struct Collected {
  std::vector<LidarScan> scans;
  std::vector<ImuSample> imu;
  std::size_t scans_before_flush = 0;
};

Collected run(OusterDecoder& decoder, const std::vector<CapturedPacket>& packets) {
  Collected out;
  DecoderSinks sinks;
  sinks.on_scan = [&](const LidarScan& s) { out.scans.push_back(s); };
  sinks.on_imu = [&](const ImuSample& s) { out.imu.push_back(s); };
  for (const auto& p : packets) decoder.on_packet(p.view(), sinks);
  out.scans_before_flush = out.scans.size();
  decoder.flush(sinks);
  return out;
}

SensorMetadata meta(const std::string& name) {
  return load_metadata(test::data_path("ouster/pcaps/" + name));
}

std::vector<CapturedPacket> capture(const std::string& name) {
  return read_capture(test::data_path("ouster/pcaps/" + name));
}

// Independent count of returns per frame id, straight from the packets.
std::map<std::uint32_t, std::size_t> returns_per_frame(const std::vector<CapturedPacket>& packets,
                                                       const PacketFormat& f) {
  std::map<std::uint32_t, std::size_t> out;
  for (const auto& p : packets) {
    LidarPacket lp;
    if (LidarPacket::parse(p.payload, f, lp) != PacketError::kNone) continue;
    for (std::uint32_t c = 0; c < lp.columns(); ++c) {
      if (!lp.column_valid(c)) continue;
      for (std::uint32_t u = 0; u < f.pixels_per_column; ++u) {
        out[lp.header().frame_id] += lp.field(c, u, ChannelField::kRange) != 0;
        out[lp.header().frame_id] += lp.field(c, u, ChannelField::kRange2) != 0;
      }
    }
  }
  return out;
}

class MovingSensor : public ::testing::Test {
 protected:
  // OS-1-128 FW 2.3 RNG15: 3 complete frames (1795-1797) of 64 packets, and 30 IMU packets.
  SensorMetadata meta_ = meta("OS-1-128_v2.3.0_1024x10.json");
  std::vector<CapturedPacket> packets_ = capture("OS-1-128_v2.3.0_1024x10_lb_n3.pcap");
  PacketFormat format_ = PacketFormat::from_metadata(meta_);

  std::vector<std::size_t> lidar_indices() const {
    std::vector<std::size_t> idx;
    for (std::size_t i = 0; i < packets_.size(); ++i) {
      if (packets_[i].payload.size() == format_.lidar_packet_size) idx.push_back(i);
    }
    return idx;
  }
};

TEST_F(MovingSensor, ThreeCompleteScans) {
  OusterDecoder decoder(meta_);
  const Collected c = run(decoder, packets_);
  ASSERT_EQ(c.scans.size(), 3U);
  EXPECT_EQ(c.scans_before_flush, 3U) << "each frame is emitted when its last column arrives";
  EXPECT_EQ(c.imu.size(), 30U);
  const DecoderCounters& k = decoder.counters();
  EXPECT_EQ(k.packets, 222U);
  EXPECT_EQ(k.lidar_packets, 192U);
  EXPECT_EQ(k.imu_packets, 30U);
  EXPECT_EQ(k.decode_errors, 0U);
  EXPECT_EQ(k.sequence_gaps, 0U);
  EXPECT_EQ(k.scans, 3U);
  EXPECT_EQ(k.incomplete_scans, 0U);
  EXPECT_EQ(decoder.ouster_counters().frame_id_gaps, 0U);
  EXPECT_EQ(decoder.model_name(), "Ouster OS-1-128");
  EXPECT_EQ(decoder.default_ports(), (std::vector<std::uint16_t>{7502, 7503}));

  const auto expected = returns_per_frame(packets_, format_);
  ASSERT_EQ(expected.size(), 3U);
  std::size_t i = 0;
  std::uint64_t total = 0;
  for (const auto& [frame_id, returns] : expected) {
    const LidarScan& s = c.scans[i];
    SCOPED_TRACE(frame_id);
    EXPECT_EQ(s.sequence, i);
    EXPECT_EQ(s.size(), returns);
    EXPECT_GT(s.size(), 100000U);
    total += returns;
    std::set<std::int32_t> offsets(s.t_offset_ns.begin(), s.t_offset_ns.end());
    EXPECT_EQ(offsets.size(), 1024U);  // one time per column
    EXPECT_EQ(*offsets.begin(), 0);
    EXPECT_NEAR(*offsets.rbegin(), 1023.0 / 1024.0 * 1e8, 1e6);  // 10 Hz
    for (std::size_t j = 1; j < s.size(); ++j) ASSERT_GE(s.t_offset_ns[j], s.t_offset_ns[j - 1]);
    EXPECT_TRUE(std::all_of(s.valid.begin(), s.valid.end(), [](std::uint8_t v) { return v == 1; }));
    EXPECT_TRUE(std::all_of(s.ring.begin(), s.ring.end(), [](std::uint16_t r) { return r < 128; }));
    EXPECT_EQ(s.start.mapped.ns, s.start.host.ns);
    ++i;
  }
  EXPECT_EQ(k.points, total);
  // The first scan starts at the first lidar packet's column 0 (sensor); its receive time is the
  // packet's, back-dated from the packet's last column to column 0 (the packet leaves once its
  // last column is measured).
  const auto first = lidar_indices().front();
  LidarPacket lp;
  ASSERT_EQ(LidarPacket::parse(packets_[first].payload, format_, lp), PacketError::kNone);
  const auto accumulation = static_cast<std::int64_t>(lp.column_timestamp_ns(lp.columns() - 1) -
                                                      lp.column_timestamp_ns(0));
  EXPECT_GT(accumulation, 1'000'000);  // 15 columns at 1024x10: 1.46 ms
  EXPECT_EQ(c.scans[0].start.host.ns, packets_[first].time_ns - accumulation);
  EXPECT_EQ(c.scans[0].start.sensor.ns, static_cast<std::int64_t>(lp.column_timestamp_ns(0)));
}

// A corrupt timestamp in the packet's last column (zeroed here) must not move the scan's receive
// time: the span back from it is negative, so nothing is back-dated; the column itself is counted
// as a timestamp jump.
TEST_F(MovingSensor, ACorruptLastColumnTimestampBackDatesNothing) {
  ASSERT_FALSE(format_.lidar_crc);  // the edit would fail the packet's CRC otherwise
  std::vector<CapturedPacket> packets = packets_;
  const auto first = lidar_indices().front();
  std::vector<std::byte>& payload = packets[first].payload;
  const std::size_t last_column =
      format_.packet_header_size + (format_.columns_per_packet - 1) * format_.column_size;
  std::fill_n(payload.begin() + static_cast<std::ptrdiff_t>(last_column), 8, std::byte{0});
  OusterDecoder decoder(meta_);
  const Collected c = run(decoder, packets);
  ASSERT_EQ(c.scans.size(), 3U);
  EXPECT_EQ(c.scans[0].start.host.ns, packets[first].time_ns);
  EXPECT_GT(decoder.ouster_counters().timestamp_jumps, 0U);
  // The other scans are back-dated as usual.
  EXPECT_LT(c.scans[1].start.host.ns - c.scans[1].start.sensor.ns,
            c.scans[0].start.host.ns - c.scans[0].start.sensor.ns);
}

TEST_F(MovingSensor, EveryPointCarriesItsColumnTime) {
  OusterDecoderOptions o;
  o.keep_invalid_points = true;  // fixed layout: point i is column i / 128, row i % 128
  OusterDecoder decoder(meta_, o);
  const Collected c = run(decoder, packets_);
  ASSERT_EQ(c.scans.size(), 3U);
  OusterDecoder plain(meta_);
  const Collected ref = run(plain, packets_);
  std::size_t scan = 0;
  std::size_t column_in_scan = 0;
  for (std::size_t i : lidar_indices()) {
    LidarPacket lp;
    ASSERT_EQ(LidarPacket::parse(packets_[i].payload, format_, lp), PacketError::kNone);
    for (std::uint32_t col = 0; col < lp.columns(); ++col, ++column_in_scan) {
      if (column_in_scan == 1024) {
        column_in_scan = 0;
        ++scan;
      }
      const LidarScan& s = c.scans[scan];
      const std::size_t point = column_in_scan * 128 + 77;
      EXPECT_EQ(s.start.sensor.ns + s.t_offset_ns[point],
                static_cast<std::int64_t>(lp.column_timestamp_ns(col)));
      EXPECT_EQ(s.ring[point], 77);
      EXPECT_EQ(s.valid[point] != 0, lp.field(col, 77, ChannelField::kRange) != 0);
    }
  }
  for (std::size_t k = 0; k < 3; ++k) {
    EXPECT_EQ(c.scans[k].size(), 128U * 1024U);
    // The valid subset is exactly the plain scan.
    std::size_t j = 0;
    for (std::size_t p = 0; p < c.scans[k].size(); ++p) {
      if (c.scans[k].valid[p] == 0) continue;
      ASSERT_LT(j, ref.scans[k].size());
      ASSERT_EQ(c.scans[k].x[p], ref.scans[k].x[j]);
      ASSERT_EQ(c.scans[k].t_offset_ns[p], ref.scans[k].t_offset_ns[j]);
      ++j;
    }
    EXPECT_EQ(j, ref.scans[k].size());
  }
  EXPECT_EQ(decoder.counters().points, plain.counters().points);
}

TEST_F(MovingSensor, MissingPacketsAndFramesAreCounted) {
  const auto lidar = lidar_indices();
  {
    // Three packets lost in the middle of the second frame.
    std::vector<CapturedPacket> lossy;
    for (std::size_t i = 0; i < packets_.size(); ++i) {
      if (i == lidar[64 + 20] || i == lidar[64 + 21] || i == lidar[64 + 40]) continue;
      lossy.push_back(packets_[i]);
    }
    OusterDecoder decoder(meta_);
    const Collected c = run(decoder, lossy);
    EXPECT_EQ(c.scans.size(), 3U);
    EXPECT_EQ(decoder.counters().sequence_gaps, 3U);
    EXPECT_EQ(decoder.counters().incomplete_scans, 1U);
    EXPECT_EQ(decoder.ouster_counters().missing_columns, 48U);
    OusterDecoderOptions drop;
    drop.incomplete_scans = IncompleteScanPolicy::kDrop;
    OusterDecoder dropping(meta_, drop);
    EXPECT_EQ(run(dropping, lossy).scans.size(), 2U);
    EXPECT_EQ(dropping.ouster_counters().dropped_incomplete_scans, 1U);
    EXPECT_EQ(dropping.counters().incomplete_scans, 1U);
  }
  {
    // The whole middle frame lost.
    std::vector<CapturedPacket> lossy;
    for (std::size_t i = 0; i < packets_.size(); ++i) {
      if (i >= lidar[64] && i <= lidar[127] &&
          packets_[i].payload.size() == format_.lidar_packet_size) {
        continue;
      }
      lossy.push_back(packets_[i]);
    }
    OusterDecoder decoder(meta_);
    const Collected c = run(decoder, lossy);
    EXPECT_EQ(c.scans.size(), 2U);
    EXPECT_EQ(decoder.ouster_counters().frame_id_gaps, 1U);
    EXPECT_EQ(decoder.counters().sequence_gaps, 64U);
    EXPECT_EQ(decoder.counters().incomplete_scans, 0U);
  }
}

// Issue 13, defect 3: a capture that starts and ends mid-frame reported the missing columns of
// its partial first and last frames as sequence gaps. They were never due: the scans are
// incomplete, nothing is lost. A packet lost between them still is.
TEST_F(MovingSensor, PartialFirstAndLastFramesAreNotLoss) {
  const auto lidar = lidar_indices();
  // Lidar packets 10 to 179 of 192: frames of 64, 54 + 64 + 52 captured.
  auto cut = [&] {
    std::vector<CapturedPacket> out;
    for (std::size_t i = 0; i < packets_.size(); ++i) {
      const bool is_lidar = packets_[i].payload.size() == format_.lidar_packet_size;
      if (is_lidar && (i < lidar[10] || i > lidar[179])) continue;
      out.push_back(packets_[i]);
    }
    return out;
  };
  {
    OusterDecoder decoder(meta_);
    const Collected c = run(decoder, cut());
    ASSERT_EQ(c.scans.size(), 3U);
    EXPECT_EQ(decoder.counters().incomplete_scans, 2U);  // the first and the last
    EXPECT_EQ(decoder.counters().sequence_gaps, 0U);     // was 10 + 12
    EXPECT_EQ(decoder.ouster_counters().missing_columns, 0U);
  }
  {
    // Lost: the first frame's second captured packet, one in the middle frame and the third
    // last captured packet (the two after it arrive).
    std::vector<CapturedPacket> kept;
    std::size_t n = 0;
    for (const auto& p : cut()) {
      if (p.payload.size() == format_.lidar_packet_size) {
        const std::size_t k = n++;
        if (k == 1 || k == 80 || k == 167) continue;
      }
      kept.push_back(p);
    }
    ASSERT_EQ(n, 170U);
    OusterDecoder decoder(meta_);
    const Collected c = run(decoder, kept);
    ASSERT_EQ(c.scans.size(), 3U);
    EXPECT_EQ(decoder.counters().sequence_gaps, 3U);
    EXPECT_EQ(decoder.ouster_counters().missing_columns, 3U * 16U);
  }
}

TEST_F(MovingSensor, LateAndDuplicatePacketsAreIgnored) {
  const auto lidar = lidar_indices();
  std::vector<CapturedPacket> noisy;
  for (std::size_t i = 0; i < packets_.size(); ++i) {
    noisy.push_back(packets_[i]);
    if (i == lidar[10]) noisy.push_back(packets_[i]);         // duplicate inside a frame
    if (i == lidar[70]) noisy.push_back(packets_[lidar[5]]);  // packet of the previous frame
  }
  OusterDecoder decoder(meta_);
  const Collected c = run(decoder, noisy);
  OusterDecoder clean(meta_);
  const Collected ref = run(clean, packets_);
  ASSERT_EQ(c.scans.size(), 3U);
  EXPECT_EQ(decoder.ouster_counters().late_packets, 2U);
  for (std::size_t k = 0; k < 3; ++k) EXPECT_EQ(c.scans[k].size(), ref.scans[k].size());
  EXPECT_EQ(decoder.counters().incomplete_scans, 0U);
}

TEST_F(MovingSensor, ReinitialisedSensorResetsTheAssembly) {
  // From the 20th packet of the second frame on, the packets carry another init_id: the sensor
  // restarted. The partial frame before the change is discarded; assembly restarts cleanly.
  const auto lidar = lidar_indices();
  std::vector<CapturedPacket> changed = packets_;
  for (std::size_t n = 64 + 20; n < lidar.size(); ++n) {
    std::vector<std::byte>& b = changed[lidar[n]].payload;
    b[4] = static_cast<std::byte>(static_cast<std::uint8_t>(b[4]) ^ 0x5A);
  }
  OusterDecoder decoder(meta_);
  const Collected c = run(decoder, changed);
  EXPECT_EQ(decoder.ouster_counters().init_id_changes, 1U);
  EXPECT_TRUE(decoder.metadata_init_id_mismatch());
  EXPECT_EQ(decoder.ouster_counters().dropped_incomplete_scans, 1U);  // first part of frame 1796
  ASSERT_EQ(c.scans.size(), 3U);  // 1795, the rest of 1796 (incomplete), 1797
  EXPECT_EQ(decoder.counters().incomplete_scans, 2U);
  EXPECT_EQ(decoder.sensor_status().init_id, *meta_.initialization_id ^ 0x5AU);
  OusterDecoder clean(meta_);
  EXPECT_FALSE(clean.metadata_init_id_mismatch());
  const Collected ref = run(clean, packets_);
  EXPECT_EQ(c.scans[0].size(), ref.scans[0].size());
  EXPECT_LT(c.scans[1].size(), ref.scans[1].size());
  EXPECT_EQ(c.scans[2].size(), ref.scans[2].size());
}

TEST_F(MovingSensor, SteadyStateDoesNotAllocate) {
  OusterDecoder decoder(meta_);
  std::size_t points = 0;
  std::size_t imu = 0;
  DecoderSinks sinks;
  sinks.on_scan = [&](const LidarScan& s) { points += s.size(); };
  sinks.on_imu = [&](const ImuSample&) { ++imu; };
  const auto lidar = lidar_indices();
  std::size_t i = 0;
  for (; i < lidar[64]; ++i) decoder.on_packet(packets_[i].view(), sinks);  // first frame
  const std::uint64_t before = g_allocations.load();
  for (; i < packets_.size(); ++i) decoder.on_packet(packets_[i].view(), sinks);
  const std::uint64_t after = g_allocations.load();
  EXPECT_EQ(after - before, 0U);
  EXPECT_EQ(decoder.counters().scans, 3U);
  EXPECT_GT(points, 300000U);
  EXPECT_EQ(imu, 30U);
}

TEST(OusterScanAssembly, CrcCaptureEndsWithAPartialFrame) {
  // crc_test: frame 254 complete (32 packets of 512 columns), then 2 packets of frame 255.
  const SensorMetadata m = meta("crc_test.json");
  const auto packets = capture("crc_test.pcap");
  OusterDecoder decoder(m);
  const Collected c = run(decoder, packets);
  ASSERT_EQ(c.scans.size(), 2U);
  EXPECT_EQ(c.scans_before_flush, 1U);
  EXPECT_EQ(decoder.counters().incomplete_scans, 1U);
  // The capture stops two packets into frame 255: the rest was never due, nothing was lost.
  EXPECT_EQ(decoder.ouster_counters().missing_columns, 0U);
  EXPECT_EQ(decoder.counters().sequence_gaps, 0U);
  EXPECT_EQ(decoder.counters().decode_errors, 0U);
  EXPECT_EQ(c.imu.size(), 10U);
  const auto expected = returns_per_frame(packets, PacketFormat::from_metadata(m));
  EXPECT_EQ(c.scans[0].size(), expected.at(254));
  EXPECT_EQ(c.scans[1].size(), expected.at(255));
  OusterDecoderOptions drop;
  drop.incomplete_scans = IncompleteScanPolicy::kDrop;
  OusterDecoder dropping(m, drop);
  EXPECT_EQ(run(dropping, packets).scans.size(), 1U);
}

TEST(OusterScanAssembly, AzimuthWindows) {
  // windowed_frame1: column window [1, 256] of 512; packets cover columns 0-271 and the sensor
  // marks the columns outside the window invalid.
  {
    const SensorMetadata m = meta("windowed_frame1_0.json");
    const auto packets = capture("windowed_frame1.pcap");
    OusterDecoder decoder(m);
    const Collected c = run(decoder, packets);
    ASSERT_EQ(c.scans.size(), 1U);
    EXPECT_EQ(c.scans_before_flush, 1U) << "emitted when column 256 arrived";
    EXPECT_EQ(decoder.counters().incomplete_scans, 0U);
    EXPECT_EQ(decoder.ouster_counters().missing_columns, 0U);
    EXPECT_EQ(decoder.ouster_counters().invalid_columns, 0U);
    EXPECT_EQ(decoder.counters().lidar_packets, 17U);
    EXPECT_EQ(c.scans[0].size(), returns_per_frame(packets, decoder.packet_format()).at(1553));
    EXPECT_EQ(decoder.default_ports(), (std::vector<std::uint16_t>{53750, 7503}));
    // Every pixel kept: 17 packets x 16 columns x 128 rows, valid only inside the window.
    OusterDecoderOptions o;
    o.keep_invalid_points = true;
    OusterDecoder all(m, o);
    const Collected k = run(all, packets);
    ASSERT_EQ(k.scans.size(), 1U);
    ASSERT_EQ(k.scans[0].size(), 17U * 16U * 128U);
    for (std::size_t i = 0; i < k.scans[0].size(); ++i) {
      const std::size_t column = i / 128;
      if (column < 1 || column > 256) {
        ASSERT_EQ(k.scans[0].valid[i], 0) << i;
      }
    }
  }
  // windowed_frame2: window [370, 85] wraps through column 0; columns 0-85 are measured first,
  // 370-511 last, all within one frame id.
  {
    const SensorMetadata m = meta("windowed_frame2_0.json");
    const auto packets = capture("windowed_frame2.pcap");
    OusterDecoder decoder(m);
    const Collected c = run(decoder, packets);
    ASSERT_EQ(c.scans.size(), 1U);
    EXPECT_EQ(c.scans_before_flush, 1U) << "emitted when column 511 arrived";
    EXPECT_EQ(decoder.counters().incomplete_scans, 0U);
    EXPECT_EQ(decoder.ouster_counters().missing_columns, 0U);
    EXPECT_EQ(decoder.counters().sequence_gaps, 0U) << "columns 96-367 are outside the window";
    EXPECT_EQ(c.scans[0].size(), returns_per_frame(packets, decoder.packet_format()).at(1314));
    EXPECT_NEAR(*std::max_element(c.scans[0].t_offset_ns.begin(), c.scans[0].t_offset_ns.end()),
                511.0 / 512.0 * 1e8, 1e6);
  }
}

TEST(OusterScanAssembly, SamePortCapturesWithFragments) {
  struct Sensor {
    std::uint32_t src;
    const char* json;
    std::size_t lidar, imu;
  };
  struct Case {
    const char* pcap;
    std::vector<Sensor> sensors;
  };
  const std::uint32_t a = ipv4(169, 254, 238, 111);
  const std::uint32_t b = ipv4(169, 254, 92, 158);
  const std::vector<Case> cases{
      {"same_ports.pcap", {{a, "same_ports.2.json", 1, 1}, {b, "same_ports.1.json", 1, 1}}},
      {"same_ports_legacy.pcap",
       {{a, "same_ports_legacy.2.json", 1, 0}, {b, "same_ports_legacy.1.json", 1, 0}}},
      {"same_ports_nonlegacy.pcap",
       {{a, "same_ports_nonlegacy.2.json", 1, 1}, {b, "same_ports_nonlegacy.1.json", 1, 1}}},
  };
  for (const Case& k : cases) {
    SCOPED_TRACE(k.pcap);
    io::PcapReader reader(test::data_path(std::string("ouster/pcaps/") + k.pcap));
    while (reader.next()) {
    }
    EXPECT_EQ(reader.stats().reassembled, 2U) << "both lidar packets arrive as IPv4 fragments";
    const auto packets = capture(k.pcap);
    for (const Sensor& s : k.sensors) {
      SCOPED_TRACE(s.json);
      std::vector<CapturedPacket> own;
      for (const auto& p : packets) {
        if (p.src_ip == s.src) own.push_back(p);
      }
      OusterDecoder decoder(meta(s.json));
      const Collected c = run(decoder, own);
      EXPECT_EQ(decoder.counters().lidar_packets, s.lidar);
      EXPECT_EQ(decoder.counters().imu_packets, s.imu);
      EXPECT_EQ(decoder.counters().decode_errors, 0U);
      ASSERT_EQ(c.scans.size(), 1U);  // one partial frame each, flushed at the end
      EXPECT_EQ(decoder.counters().incomplete_scans, 1U);
      EXPECT_EQ(c.scans[0].size(), returns_per_frame(own, decoder.packet_format()).begin()->second);
      EXPECT_GT(c.scans[0].size(), 0U);
      for (const ImuSample& imu : c.imu) EXPECT_NEAR(imu.accel_m_s2.norm(), 9.9, 0.3);
    }
  }
  // The non-colliding variant moves the IMU to 7503; classification does not depend on ports.
  EXPECT_EQ(OusterDecoder(meta("same_ports.2.non_colliding_imu.json")).default_ports(),
            (std::vector<std::uint16_t>{7502, 7503}));
  EXPECT_EQ(OusterDecoder(meta("same_ports.2.json")).default_ports(),
            (std::vector<std::uint16_t>{7502}));
}

TEST(OusterScanAssembly, DuplicateIpIdentification) {
  // duplicate_id.pcap: a stale first fragment and, 88 s later, a complete fragment set with the
  // same IPv4 id. Only the complete datagram may come out, and it must decode cleanly (a datagram
  // spliced from both would fail the measurement-id consistency check).
  const SensorMetadata m = meta("duplicate_id.json");
  const auto packets = capture("duplicate_id.pcap");
  ASSERT_EQ(packets.size(), 1U);
  const PacketFormat f = PacketFormat::from_metadata(m);
  LidarPacket lp;
  ASSERT_EQ(LidarPacket::parse(packets[0].payload, f, lp), PacketError::kNone);
  EXPECT_EQ(lp.header().frame_id, 1778U);
  EXPECT_EQ(lp.header().init_id, *m.initialization_id);
  EXPECT_EQ(lp.measurement_id(0), 432U);
  OusterDecoder decoder(m);
  const Collected c = run(decoder, packets);
  EXPECT_EQ(decoder.counters().decode_errors, 0U);
  EXPECT_FALSE(decoder.metadata_init_id_mismatch());
  ASSERT_EQ(c.scans.size(), 1U);
  EXPECT_EQ(decoder.counters().incomplete_scans, 1U);
  EXPECT_EQ(decoder.ouster_counters().missing_columns, 0U);  // one packet captured: none lost
  EXPECT_EQ(decoder.counters().sequence_gaps, 0U);
}

TEST(OusterScanAssembly, EmptyCapture) {
  const SensorMetadata m = meta("empty_pcap.json");
  const auto packets = capture("empty_pcap.pcap");
  EXPECT_TRUE(packets.empty());
  OusterDecoder decoder(m);
  const Collected c = run(decoder, packets);
  EXPECT_TRUE(c.scans.empty());
  EXPECT_EQ(decoder.counters().packets, 0U);
  EXPECT_EQ(decoder.counters().scans, 0U);
  EXPECT_EQ(decoder.counters().incomplete_scans, 0U);
}

// Issue 13, defect 5: LEGACY firmware up to 2.0 writes a 16-bit reflectivity; the intensity of
// the points (what `livod decode` writes to CSV/PCD) kept only its low 8 bits. A constructed
// packet (a real FW 2.0 packet with one channel's reflectivity set to 786) and the real capture.
TEST(OusterScanAssembly, LegacyReflectivityKeepsAllSixteenBits) {
  const SensorMetadata m = meta("OS-2-32-U0_v2.0.0_1024x10.json");
  const PacketFormat f = PacketFormat::from_metadata(m);
  ASSERT_TRUE(f.legacy_lidar());
  auto packets = capture("OS-2-32-U0_v2.0.0_1024x10.pcap");
  std::size_t first = 0;
  while (packets[first].payload.size() != f.lidar_packet_size) ++first;
  // Column 3, row 5 of the first lidar packet: range 5123 mm, reflectivity 0x0312 = 786.
  std::vector<CapturedPacket> one{packets[first]};
  std::vector<std::byte>& b = one[0].payload;
  const std::size_t column_bytes = 16 + 12 * f.pixels_per_column + 4;
  const std::size_t pixel = 3 * column_bytes + 16 + 5 * 12;
  b[pixel + 0] = std::byte{0x03};
  b[pixel + 1] = std::byte{0x14};
  b[pixel + 2] = std::byte{0x00};
  b[pixel + 4] = std::byte{0x12};
  b[pixel + 5] = std::byte{0x03};
  for (std::size_t k = 0; k < 4; ++k) b[3 * column_bytes + column_bytes - 4 + k] = std::byte{0xFF};
  OusterDecoder decoder(m);
  const Collected c = run(decoder, one);
  ASSERT_EQ(c.scans.size(), 1U);
  bool found = false;
  for (std::size_t i = 0; i < c.scans[0].size(); ++i) {
    const double r = std::sqrt(static_cast<double>(c.scans[0].x[i]) * c.scans[0].x[i] +
                               static_cast<double>(c.scans[0].y[i]) * c.scans[0].y[i] +
                               static_cast<double>(c.scans[0].z[i]) * c.scans[0].z[i]);
    if (c.scans[0].ring[i] == 5 && std::abs(r - 5.123) < 0.02) {
      EXPECT_EQ(c.scans[0].intensity[i], 786.0F);  // was 786 mod 256 = 18
      found = true;
    }
  }
  EXPECT_TRUE(found);

  // The real capture: FW 2.0 reflectivities above 255 come out whole.
  OusterDecoder whole(m);
  const Collected all = run(whole, packets);
  float highest = 0.0F;
  for (const auto& scan : all.scans) {
    for (const float v : scan.intensity) highest = std::max(highest, v);
  }
  EXPECT_GT(highest, 255.0F);
}

TEST(OusterScanAssembly, FusaDualReturns) {
  // FUSA_RNG15_RFL8_NIR8_DUAL, 8 packets of frame 229: second returns appear with index 1.
  const SensorMetadata m = meta("OS-1-128_767798045_1024x10_20230712_120049.json");
  const auto packets = capture("OS-1-128_767798045_1024x10_20230712_120049.pcap");
  OusterDecoder decoder(m);
  const Collected c = run(decoder, packets);
  EXPECT_EQ(decoder.counters().lidar_packets, 8U);
  EXPECT_EQ(decoder.counters().imu_packets, 2U);
  EXPECT_EQ(decoder.counters().decode_errors, 0U);
  ASSERT_EQ(c.scans.size(), 1U);
  const auto expected = returns_per_frame(packets, PacketFormat::from_metadata(m));
  EXPECT_EQ(c.scans[0].size(), expected.at(229));
  const auto second = std::count(c.scans[0].return_index.begin(), c.scans[0].return_index.end(), 1);
  EXPECT_GT(second, 0);
  EXPECT_LT(static_cast<std::size_t>(second), c.scans[0].size());
}

}  // namespace
}  // namespace livod::drivers::ouster

namespace livod::drivers::ouster {
namespace {

TEST(OusterFactory, BuildsFromMetadataAndRejectsMisplacedOptions) {
  DecoderConfig config;
  config.model = "OS";
  EXPECT_THROW((void)make_ouster_decoder(config), livod::Error);  // no metadata
  config.metadata = test::data_path("ouster/pcaps/crc_test.json");
  const auto decoder = make_ouster_decoder(config);
  ASSERT_NE(decoder, nullptr);
  EXPECT_EQ(decoder->model_name(), "Ouster OS-0-128");
  EXPECT_EQ(decoder->default_ports(), (std::vector<std::uint16_t>{7502, 7503}));
  std::size_t scans = 0;
  DecoderSinks sinks;
  sinks.on_scan = [&](const LidarScan&) { ++scans; };
  for (const auto& p : read_capture(test::data_path("ouster/pcaps/crc_test.pcap"))) {
    decoder->on_packet(p.view(), sinks);
  }
  decoder->flush(sinks);
  EXPECT_EQ(scans, 2U);
  config.calibration = test::data_path("ouster/pcaps/crc_test.json");
  EXPECT_THROW((void)make_ouster_decoder(config), livod::Error);
  config.calibration.reset();
  config.metadata = test::data_path("ouster/metadata/malformed/garbled_legacy_and_nonlegacy.json");
  EXPECT_THROW((void)make_ouster_decoder(config), MetadataError);
}

}  // namespace
}  // namespace livod::drivers::ouster

namespace livod::drivers::ouster {
namespace {

TEST(OusterFactory, InconsistentHandBuiltMetadataIsRefused) {
  SensorMetadata m = load_metadata(test::data_path("ouster/pcaps/crc_test.json"));
  m.beam_azimuth_angles_deg.pop_back();
  EXPECT_THROW(OusterDecoder{m}, livod::Error);
  m = load_metadata(test::data_path("ouster/pcaps/crc_test.json"));
  m.format.column_window.last = m.format.columns_per_frame;
  EXPECT_THROW(OusterDecoder{m}, livod::Error);
}

}  // namespace
}  // namespace livod::drivers::ouster
