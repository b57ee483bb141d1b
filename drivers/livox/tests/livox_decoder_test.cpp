#include "drivers/livox/livox_decoder.hpp"

#include <gtest/gtest.h>

#include <vector>

namespace livod::livox {
namespace {

struct Collected {
  std::vector<LidarScan> scans;
  std::vector<ImuSample> imu;
  drivers::DecoderSinks sinks() {
    return {[this](const LidarScan& s) { scans.push_back(s); },
            [this](const ImuSample& s) { imu.push_back(s); }};
  }
};

std::array<LivoxPoint, 96> points(float x) {
  std::array<LivoxPoint, 96> pts{};
  for (auto& p : pts) {
    p.x = x;
    p.y = 1.0F;
    p.z = 0.5F;
    p.valid = true;
  }
  return pts;
}

// One Mid-360 point packet: 96 points over 475 us starting at t_ns.
std::vector<std::byte> mid360_packet(std::int64_t t_ns, int udp_cnt,
                                     const std::array<LivoxPoint, 96>& pts) {
  Sdk2Header h;
  h.timestamp_ns = static_cast<std::uint64_t>(t_ns);
  h.time_interval_100ns = 4750;
  h.udp_cnt = static_cast<std::uint16_t>(udp_cnt);
  return encode_sdk2_points(h, pts);
}

TEST(LivoxDecoder, Mid360StreamIsCutIntoPeriodAlignedScansAndCountsGaps) {
  LivoxDecoder dec(*livox_model("MID-360"), LivoxDecoderOptions{});
  Collected out;
  // 200 kpts/s: 96 points per 480 us packet. 0.35 s of packets starting at t = 1.02 s, with
  // packet 100 missing, and one IMU packet.
  const std::int64_t t0 = 1'020'000'000;
  const auto pts = points(4.0F);
  int sent = 0;
  for (int k = 0; k < 730; ++k) {
    if (k == 100) continue;
    const auto bytes = mid360_packet(t0 + k * 480'000LL, k, pts);
    dec.on_packet({bytes, t0 + k * 480'000LL + 600'000, 56301}, out.sinks());
    ++sent;
  }
  const auto imu =
      encode_sdk2_imu(Sdk2Header{}, Eigen::Vector3d(0, 0, 0.1), Eigen::Vector3d(0, 0, 9.8));
  dec.on_packet({imu, 5, 56401}, out.sinks());
  dec.flush(out.sinks());

  EXPECT_EQ(dec.counters().sequence_gaps, 1u);
  EXPECT_EQ(dec.counters().lidar_packets, static_cast<std::uint64_t>(sent));
  ASSERT_EQ(out.imu.size(), 1u);
  EXPECT_NEAR(out.imu[0].accel_m_s2.z(), 9.8, 1e-5);
  // Points span [1.02, 1.3704) s: scans [1.0,1.1) partial, [1.1,1.2), [1.2,1.3), [1.3,1.4) partial.
  ASSERT_EQ(out.scans.size(), 4u);
  std::size_t total = 0;
  for (std::size_t i = 0; i < out.scans.size(); ++i) {
    const auto& s = out.scans[i];
    EXPECT_EQ(s.sequence, i);
    EXPECT_EQ(s.start.sensor.ns, 1'000'000'000 + static_cast<std::int64_t>(i) * 100'000'000);
    for (std::size_t p = 0; p < s.size(); ++p) {
      ASSERT_GE(s.t_offset_ns[p], 0);
      ASSERT_LT(s.t_offset_ns[p], 100'000'000);
    }
    total += s.size();
  }
  EXPECT_EQ(total, static_cast<std::size_t>(sent) * 96);
  EXPECT_EQ(out.scans[0].t_offset_ns.front(), 20'000'000);
  // Host time of a scan start = rx - packet span + point offset - (point time - window start).
  EXPECT_EQ(out.scans[1].start.host.ns - out.scans[1].start.sensor.ns, 600'000 - 475'000);
}

TEST(LivoxDecoder, AviaSdk1GapsFromTimestampsAndMalformedPacketsAreCounted) {
  LivoxDecoder dec(*livox_model("AVIA"), LivoxDecoderOptions{});
  Collected out;
  const auto pts = points(2.0F);
  const std::int64_t span = 96LL * 4167;  // one packet: 96 points at 4167 ns
  for (int k = 0; k < 50; ++k) {
    if (k == 10 || k == 11) continue;  // two packets lost
    Sdk1Header h;
    h.timestamp = static_cast<std::uint64_t>(k * span);
    const auto bytes = encode_sdk1_points(h, pts);
    dec.on_packet({bytes, k * span, 56001}, out.sinks());
  }
  std::vector<std::byte> junk(40, std::byte{0x55});
  dec.on_packet({junk, 0, 56001}, out.sinks());
  dec.flush(out.sinks());
  EXPECT_EQ(dec.counters().sequence_gaps, 2u);
  EXPECT_EQ(dec.counters().decode_errors, 1u);
  EXPECT_EQ(dec.decode_error_count(DecodeError::kBadVersion), 1u);
  ASSERT_EQ(out.scans.size(), 1u);
  EXPECT_EQ(out.scans[0].size(), 48u * 96u);
  EXPECT_EQ(out.scans[0].ring[7], 1);  // line = point index mod 6
}

TEST(LivoxDecoder, ALatePacketIsDroppedWithoutSplittingTheScan) {
  // Mid-360 packets 0.48 ms apart across the 1.1 s window boundary; packet 5 (in the first window)
  // is delivered after packet 12 (in the second): the link delayed it. The scan of the second
  // window must not be split, the late points are counted, and the reordering is no gap.
  LivoxDecoder dec(*livox_model("MID-360"), LivoxDecoderOptions{});
  Collected out;
  const auto pts = points(3.0F);
  const std::int64_t t0 = 1'097'120'000;  // packet 5 ends at 1.099995 s, packet 6 starts at 1.1 s
  auto send = [&](int k) {
    const auto bytes = mid360_packet(t0 + k * 480'000LL, k, pts);
    dec.on_packet({bytes, t0 + k * 480'000LL + 600'000, 56301}, out.sinks());
  };
  for (int k = 0; k < 20; ++k) {
    if (k == 5) continue;
    send(k);
    if (k == 12) send(5);
  }
  dec.flush(out.sinks());
  // Windows [1.0, 1.1) (packets 0..4 and 5 were due there) and [1.1, 1.2).
  ASSERT_EQ(out.scans.size(), 2U);
  EXPECT_EQ(out.scans[0].start.sensor.ns, 1'000'000'000);
  EXPECT_EQ(out.scans[1].start.sensor.ns, 1'100'000'000);
  EXPECT_EQ(dec.counters().late_points, 96U);
  EXPECT_EQ(dec.counters().sequence_gaps, 0U);
  EXPECT_EQ(out.scans[0].size() + out.scans[1].size(), 19U * 96U);
}

TEST(LivoxDecoder, AClockResetRestartsTheTimeline) {
  LivoxDecoder dec(*livox_model("MID-360"), LivoxDecoderOptions{});
  Collected out;
  const auto pts = points(3.0F);
  auto send = [&](std::int64_t t, int k) {
    const auto bytes = mid360_packet(t, k, pts);
    dec.on_packet({bytes, t, 56301}, out.sinks());
  };
  for (int k = 0; k < 400; ++k) send(50'000'000'000LL + k * 480'000LL, k);
  // The sensor restarted: its clock counts from zero again.
  for (int k = 0; k < 400; ++k) send(k * 480'000LL, 400 + k);
  dec.flush(out.sinks());
  EXPECT_EQ(dec.counters().late_points, 0U);
  std::size_t total = 0;
  for (const auto& s : out.scans) total += s.size();
  EXPECT_EQ(total, 800U * 96U);
  EXPECT_EQ(out.scans.back().start.sensor.ns, 100'000'000);
  EXPECT_EQ(dec.counters().clock_jumps, 1U);
  EXPECT_EQ(dec.counters().sequence_gaps, 0U);
}

// Issue 13, defect 1: a Velodyne capture decoded as an Avia gave ~20 000 garbage points and fake
// IMU samples with no decode error. Every foreign datagram is an error and yields nothing.
TEST(LivoxDecoder, ForeignTrafficYieldsNoPointsAndNoImu) {
  for (const char* model : {"AVIA", "HORIZON", "TELE-15", "MID-40", "MID-70", "MID-360", "HAP"}) {
    LivoxDecoder dec(*livox_model(model), LivoxDecoderOptions{});
    Collected out;
    std::vector<std::byte> velodyne(1206, std::byte{0x20});
    std::vector<std::byte> position(512, std::byte{0x00});
    // An SDK1 header with a foreign version byte and 100 trailing bytes.
    Sdk1Header h;
    auto foreign = encode_sdk1_points(h, points(1.0F));
    foreign[0] = std::byte{0xFF};
    foreign.insert(foreign.end(), 100, std::byte{1});
    for (int k = 0; k < 50; ++k) {
      for (std::size_t b = 0; b < 12; ++b) {
        velodyne[b * 100] = std::byte{0xFF};
        velodyne[b * 100 + 1] = std::byte{0xEE};
        velodyne[b * 100 + 9] = static_cast<std::byte>(k % 9);
      }
      dec.on_packet({velodyne, k * 1'000'000LL, 2368}, out.sinks());
      dec.on_packet({position, k * 1'000'000LL, 8308}, out.sinks());
      dec.on_packet({foreign, k * 1'000'000LL, 56001}, out.sinks());
    }
    dec.flush(out.sinks());
    EXPECT_TRUE(out.scans.empty()) << model;
    EXPECT_TRUE(out.imu.empty()) << model;
    EXPECT_EQ(dec.counters().decode_errors, 150U) << model;
    EXPECT_EQ(dec.counters().lidar_packets + dec.counters().imu_packets, 0U) << model;
  }
}

// Issue 13, defect 2: an SDK1 sensor whose clock jumps forward (it gains PTP or GPS sync
// mid-stream) reported 4 249 660 024 696 sequence gaps. The jump is a clock event; only the
// packets really lost (one before the jump, two after) are gaps.
TEST(LivoxDecoder, Sdk1ForwardClockJumpIsAClockEventNotLoss) {
  LivoxDecoder dec(*livox_model("AVIA"), LivoxDecoderOptions{});
  Collected out;
  const auto pts = points(2.0F);
  const std::int64_t span = 96LL * 4167;
  const std::int64_t host0 = 7'000'000'000;
  auto send = [&](std::uint64_t ts, std::uint8_t type, std::int64_t host) {
    Sdk1Header h;
    h.timestamp = ts;
    h.timestamp_type = type;
    const auto bytes = encode_sdk1_points(h, pts);
    dec.on_packet({bytes, host, 56001}, out.sinks());
  };
  // Free-running (type 0) from 12 s after power-on, packet 20 lost.
  for (int k = 0; k < 100; ++k) {
    if (k == 20) continue;
    send(12'000'000'000ULL + static_cast<std::uint64_t>(k * span), 0, host0 + k * span);
  }
  // PTP locks: same timestamp type field in some firmware, epoch time 1.7e9 s from now on.
  const std::uint64_t epoch = 1'700'000'000'000'000'000ULL;
  for (int k = 100; k < 200; ++k) {
    if (k == 150 || k == 151) continue;
    send(epoch + static_cast<std::uint64_t>(k * span), 0, host0 + k * span);
  }
  // And the timestamp type changes (type 1, PTP) with a small step.
  for (int k = 200; k < 220; ++k) {
    send(epoch + static_cast<std::uint64_t>(k * span) + 5'000, 1, host0 + k * span);
  }
  dec.flush(out.sinks());
  EXPECT_EQ(dec.counters().sequence_gaps, 3U);
  EXPECT_EQ(dec.counters().clock_jumps, 2U);
  EXPECT_EQ(dec.counters().late_points, 0U);
  std::size_t total = 0;
  for (const auto& s : out.scans) total += s.size();
  EXPECT_EQ(total, 217U * 96U);
}

// A real outage: the receive times advance with the sensor times, so the missing packets are
// counted (bounded by the elapsed time, not by the timestamps alone).
TEST(LivoxDecoder, Sdk1OutageConsistentWithReceiveTimeIsCountedAsGaps) {
  LivoxDecoder dec(*livox_model("MID-70"), LivoxDecoderOptions{});
  Collected out;
  std::array<LivoxPoint, 96> pts96 = points(2.0F);
  const std::int64_t span = 96LL * 10'000;  // Mid-70 type 2: 96 points, 10 us apart
  for (int k = 0; k < 3000; ++k) {
    if (k >= 100 && k < 2700) continue;  // 2.5 s without data (cable pulled)
    Sdk1Header h;
    h.timestamp = static_cast<std::uint64_t>(k * span);
    const auto bytes = encode_sdk1_points(h, pts96);
    dec.on_packet({bytes, k * span + 300'000, 56001}, out.sinks());
  }
  EXPECT_EQ(dec.counters().sequence_gaps, 2600U);
  EXPECT_EQ(dec.counters().clock_jumps, 0U);
}

TEST(LivoxDecoder, KnowsTheModelsAndTheirPorts) {
  EXPECT_FALSE(livox_model("VLP-16"));
  LivoxDecoder mid(*livox_model("MID-360"), {});
  EXPECT_EQ(mid.default_ports(), (std::vector<std::uint16_t>{56301, 56401}));
  LivoxDecoder avia(*livox_model("AVIA"), {});
  EXPECT_EQ(avia.default_ports(), (std::vector<std::uint16_t>{56001}));
}

}  // namespace
}  // namespace livod::livox
