// HesaiDecoder on constructed streams: firing times, loss from the UDP sequence and from the
// timestamps, late packets, clock jumps, the start/end angle window, cut modes, dual return,
// foreign traffic and the calibration it requires.

#include "drivers/hesai/hesai_decoder.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <fstream>

#include "core/error.hpp"
#include "tests/support/data_dir.hpp"

namespace livod::drivers::hesai {
namespace {

constexpr std::int64_t kBaseNs = 1'700'000'000'000'000'000LL;  // a whole second, UTC

AngleCorrections nominal(Model model) {
  AngleCorrections k;
  k.source = "test";
  const int n = traits(model).channels;
  for (int c = 0; c < n; ++c) k.channels.push_back({15.0 - c, 0.0});
  return k;
}

struct StreamOptions {
  Model model = Model::kPandarXT32;
  bool dual = false;
  bool sequence = true;
  // Start/end angle window: rounds outside are not sent; `sequence_counts_skipped` makes the
  // UDP sequence advance over the packets of the skipped sector (Hesai's "UDP sequence ON #2").
  std::optional<AzimuthWindow> window;
  bool sequence_counts_skipped = false;
};

// 10 Hz: XT32 rounds every 50 us (0.18 deg), 40P every 55.56 us (0.2 deg). Range of round k,
// channel c: 1000 + (k mod 50000) ... (x 4 mm) so points can be traced to their round.
struct Stream {
  std::vector<std::vector<std::byte>> packets;
  std::vector<std::int64_t> host_ns;
  std::vector<std::int64_t> round_time_ns;  // per round k
};

Stream make_stream(const StreamOptions& o, double seconds) {
  const ModelTraits& t = traits(o.model);
  const int returns = o.dual ? 2 : 1;
  const int rounds_per_packet = t.blocks / returns;
  const double step_centideg = o.model == Model::kPandarXT32 ? 18.0 : 20.0;
  const double round_ns = o.model == Model::kPandarXT32 ? 50'000.0 : 55'560.0;
  const FiringTiming timing(o.model);
  Stream s;
  const auto packets = static_cast<int>(seconds * 1e9 / (round_ns * rounds_per_packet));
  std::uint32_t sequence = 1000;
  int k = 0;
  for (int j = 0; j < packets; ++j, k += rounds_per_packet) {
    HesaiPacket p;
    p.model = o.model;
    p.returns = returns;
    p.return_mode = o.dual ? 0x39 : 0x37;
    p.first_block_return = o.dual ? 1 : 0;
    p.motor_rpm = 600;
    bool outside = false;
    for (int r = 0; r < rounds_per_packet; ++r) {
      const int round = k + r;
      const auto azimuth = static_cast<std::uint16_t>(std::llround(round * step_centideg) % 36000);
      if (o.window) {
        const int start = static_cast<int>(std::lround(o.window->start_deg * 100)) % 36000;
        const int length = 36000 - o.window->skipped_length_centideg();
        if ((azimuth - start + 36000) % 36000 >= length) outside = true;
      }
      for (int b = r * returns; b < (r + 1) * returns; ++b) {
        p.azimuth[static_cast<std::size_t>(b)] = azimuth;
        for (int c = 0; c < t.channels; ++c) {
          const auto i = static_cast<std::size_t>(b * kMaxChannels + c);
          // Dual: the second block repeats the first (one echo) on even channels.
          const int extra = (o.dual && (b % 2 == 1) && (c % 2 == 1)) ? 7 : 0;
          p.distance[i] = static_cast<std::uint16_t>(1000 + round % 50000 + extra);
          p.reflectivity[i] = static_cast<std::uint8_t>(b % 2 == 0 ? 50 : 40);
        }
      }
    }
    // The packet time: the last round's reference instant.
    const double last_round_ns = (k + rounds_per_packet - 1) * round_ns;
    const std::int64_t t0 =
        kBaseNs + std::llround(last_round_ns) - timing.block_start_ns(o.dual, t.blocks - 1);
    p.timestamp_ns = t0 / 1000 * 1000;  // the tail carries microseconds
    for (int r = 0; r < rounds_per_packet; ++r) {
      s.round_time_ns.push_back(kBaseNs + std::llround((k + r) * round_ns));
    }
    if (outside) {
      if (o.sequence_counts_skipped) ++sequence;
      continue;
    }
    if (o.sequence) p.udp_sequence = sequence++;
    s.packets.push_back(encode_packet(p));
    s.host_ns.push_back(p.timestamp_ns + 300'000);
  }
  return s;
}

struct Result {
  std::vector<LidarScan> scans;
  DecoderCounters counters;
  HesaiCounters hesai;
};

template <class Edit>
Result run(const Stream& s, HesaiOptions options, Edit edit) {
  HesaiDecoder decoder(options, nominal(options.model));
  Result out;
  DecoderSinks sinks;
  sinks.on_scan = [&out](const LidarScan& scan) { out.scans.push_back(scan); };
  for (std::size_t i = 0; i < s.packets.size(); ++i) {
    std::vector<std::byte> bytes = s.packets[i];
    std::int64_t host = s.host_ns[i];
    if (!edit(i, bytes, host)) continue;
    decoder.on_packet({bytes, host, kDataPort}, sinks);
  }
  decoder.flush(sinks);
  out.counters = decoder.counters();
  out.hesai = decoder.hesai_counters();
  return out;
}

Result run(const Stream& s, HesaiOptions options) {
  return run(s, options, [](std::size_t, std::vector<std::byte>&, std::int64_t&) { return true; });
}

HesaiOptions options_for(Model model) {
  HesaiOptions o;
  o.model = model;
  return o;
}

// Every point's time against its round's true time plus the channel's offset in the round.
void expect_firing_times(const Result& r, const Stream& s, Model model) {
  const FiringTiming timing(model);
  const ModelTraits& t = traits(model);
  std::size_t checked = 0;
  for (const auto& scan : r.scans) {
    for (std::size_t i = 0; i < scan.size(); ++i) {
      const double d = std::sqrt(static_cast<double>(scan.x[i]) * scan.x[i] +
                                 static_cast<double>(scan.y[i]) * scan.y[i] +
                                 static_cast<double>(scan.z[i]) * scan.z[i]);
      const int round = static_cast<int>(std::lround(d / 0.004)) - 1000;
      if (round < 0 || round >= static_cast<int>(s.round_time_ns.size())) continue;
      // Channel from the ring (nominal corrections: channel 0 is the highest beam).
      const int c = t.channels - 1 - scan.ring[i];
      const std::int64_t expected =
          s.round_time_ns[static_cast<std::size_t>(round)] +
          (timing.offset_ns(false, t.blocks - 1, c) - timing.block_start_ns(false, t.blocks - 1));
      const std::int64_t got = scan.start.sensor.ns + scan.t_offset_ns[i];
      ASSERT_NEAR(static_cast<double>(got - expected), 0.0, 1'000.0) << "round " << round;
      ++checked;
    }
  }
  EXPECT_GT(checked, 10'000U);
}

TEST(HesaiDecoder, Xt32PointTimesFollowTheFiringTable) {
  const Stream s = make_stream({}, 0.25);
  const Result r = run(s, options_for(Model::kPandarXT32));
  EXPECT_EQ(r.counters.decode_errors, 0U);
  EXPECT_EQ(r.counters.sequence_gaps, 0U);
  expect_firing_times(r, s, Model::kPandarXT32);
}

TEST(HesaiDecoder, Pandar40pPointTimesFollowTheFiringTable) {
  StreamOptions o;
  o.model = Model::kPandar40P;
  o.sequence = false;
  const Stream s = make_stream(o, 0.25);
  const Result r = run(s, options_for(Model::kPandar40P));
  EXPECT_EQ(r.counters.decode_errors, 0U);
  EXPECT_EQ(r.counters.sequence_gaps, 0U);
  expect_firing_times(r, s, Model::kPandar40P);
  // Laser 8 fires first in a round (54.67 us before the round's end), lasers 4 and 40 last.
  const FiringTiming timing(Model::kPandar40P);
  EXPECT_EQ(timing.offset_ns(false, 9, 3) - timing.offset_ns(false, 9, 7), 54'670 - 3'620);
  EXPECT_EQ(timing.offset_ns(false, 9, 39), timing.offset_ns(false, 9, 3));
  EXPECT_EQ(timing.offset_ns(false, 9, 0) - timing.offset_ns(false, 8, 0), 55'560);
  EXPECT_EQ(timing.offset_ns(true, 9, 0), timing.offset_ns(true, 8, 0));
}

// A packet leaves once its last round has fired; a scan's receive stamp is back-dated from its
// packet's to its first point, so that a clock fed by scans alone (docs/clocks.md) sees the link
// delay only, wherever in its packet the scan was cut. The stream's packets arrive 300 us after
// their packet time: every scan start then reads 300 us less the last firing's offset from it.
TEST(HesaiDecoder, ScanStartsAreBackDatedToTheirFirstPoint) {
  for (const Model model : {Model::kPandarXT32, Model::kPandar40P}) {
    StreamOptions so;
    so.model = model;
    so.sequence = model == Model::kPandarXT32;
    const Stream s = make_stream(so, 0.55);
    HesaiOptions o = options_for(model);
    o.cut_angle_deg = 90.5;  // inside a packet
    const Result r = run(s, o);
    ASSERT_GE(r.scans.size(), 6U);
    const FiringTiming timing(model);
    const ModelTraits& t = traits(model);
    std::int32_t last = timing.offset_ns(false, t.blocks - 1, 0);
    for (int c = 1; c < t.channels; ++c) {
      last = std::max(last, timing.offset_ns(false, t.blocks - 1, c));
    }
    for (const LidarScan& scan : r.scans) {
      EXPECT_EQ(scan.start.host.ns - scan.start.sensor.ns, 300'000 - last);
    }
  }
}

TEST(HesaiDecoder, AzimuthCutMakesWholeTurns) {
  const Stream s = make_stream({}, 0.55);
  HesaiOptions o = options_for(Model::kPandarXT32);
  o.cut_angle_deg = 90.0;
  const Result r = run(s, o);
  // 0.55 s from azimuth 0 (11000 rounds, 2000 a turn): rounds 0-499 before 90 degrees, five
  // turns, and rounds 10500-10999.
  ASSERT_EQ(r.scans.size(), 7U);
  EXPECT_EQ(r.counters.incomplete_scans, 2U);
  for (std::size_t k = 1; k + 1 < r.scans.size(); ++k) {
    EXPECT_EQ(r.scans[k].size(), 2000U * 32U) << k;  // 2000 rounds per turn at 10 Hz
    // Starts at the first round at or after 90 degrees.
    const double a =
        std::atan2(-static_cast<double>(r.scans[k].y[0]), r.scans[k].x[0]) * 18000.0 / M_PI;
    EXPECT_NEAR(a, 9000.0, 18.0) << k;
  }
}

TEST(HesaiDecoder, TimeCutAlignsScansToThePeriodGrid) {
  const Stream s = make_stream({}, 0.35);
  HesaiOptions o = options_for(Model::kPandarXT32);
  o.cut = ScanCut::kTimePeriod;
  o.cut_period_ns = 50'000'000;
  const Result r = run(s, o);
  ASSERT_GE(r.scans.size(), 7U);
  std::size_t total = 0;
  for (std::size_t k = 0; k < r.scans.size(); ++k) {
    total += r.scans[k].size();
    const std::int64_t start = r.scans[k].start.sensor.ns;
    if (k > 0) {
      EXPECT_EQ(start % 50'000'000, 0) << k;  // rounds fall on the grid here
    }
  }
  EXPECT_EQ(total, s.packets.size() * 8U * 32U);
}

TEST(HesaiDecoder, UdpSequenceCountsLostLateAndRepeatedPackets) {
  const Stream s = make_stream({}, 0.3);
  const Result r = run(s, options_for(Model::kPandarXT32),
                       [&](std::size_t i, std::vector<std::byte>&, std::int64_t&) {
                         return i != 100 && i != 101 && i != 400;  // three lost
                       });
  EXPECT_EQ(r.counters.sequence_gaps, 3U);
  EXPECT_GE(r.counters.incomplete_scans, 3U);

  // A repeated packet and one delivered after its successor are late: dropped, not gaps.
  HesaiDecoder decoder(options_for(Model::kPandarXT32), nominal(Model::kPandarXT32));
  DecoderSinks sinks;
  std::size_t points = 0;
  sinks.on_scan = [&](const LidarScan& scan) { points += scan.size(); };
  for (std::size_t i = 0; i < s.packets.size(); ++i) {
    if (i == 50) continue;
    decoder.on_packet({s.packets[i], s.host_ns[i], kDataPort}, sinks);
    if (i == 51) decoder.on_packet({s.packets[50], s.host_ns[51], kDataPort}, sinks);
    if (i == 60) decoder.on_packet({s.packets[60], s.host_ns[60], kDataPort}, sinks);
  }
  decoder.flush(sinks);
  EXPECT_EQ(decoder.hesai_counters().late_packets, 2U);
  EXPECT_EQ(decoder.counters().sequence_gaps, 1U);  // packet 50 never came in time
  EXPECT_EQ(points, (s.packets.size() - 1) * 8U * 32U);
}

TEST(HesaiDecoder, TimestampsCountLossWithoutSequenceAndClockJumpsAreNoLoss) {
  StreamOptions so;
  so.model = Model::kPandar40P;
  so.sequence = false;
  const Stream s = make_stream(so, 0.3);
  const Result lossy =
      run(s, options_for(Model::kPandar40P),
          [](std::size_t i, std::vector<std::byte>&, std::int64_t&) { return i != 20 && i != 21; });
  EXPECT_EQ(lossy.counters.sequence_gaps, 2U);

  // The sensor acquires PTP: its clock steps forward by an hour while the receive times go on.
  const Result jumped = run(s, options_for(Model::kPandar40P),
                            [](std::size_t i, std::vector<std::byte>& b, std::int64_t&) {
                              if (i >= 200)
                                b[1259] = static_cast<std::byte>(static_cast<int>(b[1259]) + 1);
                              return true;
                            });
  EXPECT_EQ(jumped.counters.clock_jumps, 1U);
  EXPECT_EQ(jumped.counters.sequence_gaps, 0U);
  EXPECT_EQ(jumped.hesai.late_packets, 0U);
}

TEST(HesaiDecoder, StartEndAngleWindowIsNoLoss) {
  StreamOptions so;
  so.window = AzimuthWindow{30.0, 200.0};
  so.sequence_counts_skipped = true;  // UDP sequence ON #2: counts the packets not sent
  const Stream s = make_stream(so, 0.55);
  HesaiOptions o = options_for(Model::kPandarXT32);
  o.fov = so.window;
  const Result r = run(s, o);
  EXPECT_EQ(r.counters.sequence_gaps, 0U);
  EXPECT_EQ(r.counters.incomplete_scans, 2U);  // first and last only
  // Without the window the skipped sector looks like loss (about 190/360 of a turn per turn).
  const Result unaware = run(s, options_for(Model::kPandarXT32));
  EXPECT_GT(unaware.counters.sequence_gaps, 500U);
  // A real loss inside the window still counts.
  const Result lossy =
      run(s, o, [](std::size_t i, std::vector<std::byte>&, std::int64_t&) { return i != 150; });
  EXPECT_EQ(lossy.counters.sequence_gaps, 1U);

  // Without a sequence number (Pandar40P default) the timestamps tell, and the window again.
  StreamOptions p40 = so;
  p40.model = Model::kPandar40P;
  p40.sequence = false;
  p40.window = AzimuthWindow{300.0, 100.0};
  const Stream s40 = make_stream(p40, 0.55);
  HesaiOptions o40 = options_for(Model::kPandar40P);
  o40.fov = p40.window;
  EXPECT_EQ(run(s40, o40).counters.sequence_gaps, 0U);
}

TEST(HesaiDecoder, DualReturnDropsCoincidingEchoesAndRanksTheOthers) {
  StreamOptions so;
  so.dual = true;
  const Stream s = make_stream(so, 0.15);
  const Result r = run(s, options_for(Model::kPandarXT32));
  std::size_t first = 0;
  std::size_t second = 0;
  for (const auto& scan : r.scans) {
    for (const auto k : scan.return_index) (k == 0 ? first : second) += 1;
  }
  // Per round: 32 channels in the first block; the second block repeats 16 (dropped) and has 16
  // further echoes, weaker (reflectivity 40 < 50): return_index 1.
  const std::size_t rounds = s.packets.size() * 4U;
  EXPECT_EQ(first, rounds * 32U);
  EXPECT_EQ(second, rounds * 16U);
  EXPECT_EQ(r.hesai.duplicate_returns, rounds * 16U);
}

TEST(HesaiDecoder, ForeignTrafficIsCountedAndYieldsNothing) {
  HesaiDecoder decoder(options_for(Model::kPandarXT32), nominal(Model::kPandarXT32));
  DecoderSinks sinks;
  std::size_t scans = 0;
  sinks.on_scan = [&](const LidarScan&) { ++scans; };
  std::vector<std::byte> velodyne(1206, std::byte{0xFF});
  std::vector<std::byte> ouster(3392, std::byte{0x01});
  std::vector<std::byte> gps(512, std::byte{0});
  gps[0] = std::byte{0xFF};
  gps[1] = std::byte{0xEE};
  for (int k = 0; k < 10; ++k) {
    decoder.on_packet({velodyne, k, kDataPort}, sinks);
    decoder.on_packet({ouster, k, kDataPort}, sinks);
    decoder.on_packet({gps, k, kGpsPort}, sinks);
  }
  decoder.flush(sinks);
  EXPECT_EQ(scans, 0U);
  EXPECT_EQ(decoder.counters().decode_errors, 20U);
  EXPECT_EQ(decoder.counters().aux_packets, 10U);
  EXPECT_EQ(decoder.hesai_counters().gps_packets, 10U);
  EXPECT_EQ(
      decoder.hesai_counters().packet_errors[static_cast<std::size_t>(PacketError::kWrongSize)],
      20U);
}

TEST(HesaiDecoder, NeedsAnAngleCorrectionFileOfTheModel) {
  HesaiOptions o = options_for(Model::kPandarXT32);
  EXPECT_THROW(HesaiDecoder{o}, Error);                              // no calibration
  EXPECT_THROW(HesaiDecoder(o, nominal(Model::kPandar40P)), Error);  // 40 channels
  o.calibration_file = test::data_path("hesai/PandarXT32.csv");
  EXPECT_NO_THROW(HesaiDecoder{o});
  o.model = Model::kPandar40P;
  EXPECT_THROW(HesaiDecoder{o}, Error);
}

}  // namespace
}  // namespace livod::drivers::hesai
