#include "drivers/imu/xsens_mtdata2.hpp"

#include <gtest/gtest.h>

#include <random>
#include <sstream>
#include <vector>

namespace livod::imu {
namespace {

// MTData2 payloads recorded from a real MTi-300 (firmware 1.8.2) with Xsens MT Manager, and the
// values MT Manager decoded from them (a public "XSens Golden Packets" reference note; the bytes
// are test vectors, not code). Item order: PacketCounter, SampleTimeFine, Quaternion,
// Acceleration, DeltaV, FreeAcceleration, RateOfTurn, DeltaQ, [MagneticField], ..., StatusWord.
std::vector<std::uint8_t> hex(const std::string& text) {
  std::vector<std::uint8_t> out;
  std::istringstream in(text);
  std::string byte;
  while (in >> byte) out.push_back(static_cast<std::uint8_t>(std::stoul(byte, nullptr, 16)));
  return out;
}

const char* const kGolden1 =
    "10 20 02 A6 55 10 60 04 00 57 47 2E 20 10 10 3F 7F 7D C4 BC 10 10 7D 3B A1 57 70 BD 7E C6 56 "
    "40 20 0C BD A2 1A F8 BE 2A 8E 96 41 1D 27 A2 40 10 0C B9 4F C8 00 B9 DA 24 00 3C C9 28 80 40 "
    "30 0C 3C 02 C8 9C 3C 35 F6 C8 3C DB 0C 00 80 20 0C BB B1 7D 81 BB 96 32 00 3C 01 E8 41 80 30 "
    "10 3F 80 00 00 B6 E3 30 01 B6 C0 40 00 37 26 48 00 C0 20 0C BE 99 9C 24 3F B6 1B 56 3F 16 6A "
    "EB 30 10 04 00 01 86 DE E0 20 04 00 40 00 03";
const char* const kGolden3 =
    "10 20 02 8D 90 10 60 04 00 54 DB F1 20 10 10 3F 7F 89 11 BC 11 1D FA 3B A0 CE F0 BD 73 25 73 "
    "40 20 0C BD DC F9 D0 BE 3C 86 19 41 1D 0B 47 40 10 0C B9 8D B0 00 B9 F1 48 00 3C C9 04 30 40 "
    "30 0C BC B9 89 2E BB 09 8C 00 3C A7 08 00 80 20 0C BA 63 BC 01 BC 04 D6 3F BB 6D E3 FE 80 30 "
    "10 3F 80 00 01 B5 91 C0 00 B7 2A 08 00 B6 98 40 00 E0 20 04 00 40 00 03";
// Recorded during a hard shake: accelerometer z and gyroscope y clip (status bits 10 and 12).
const char* const kGolden5 =
    "10 20 02 FB 85 10 60 04 01 A4 98 DE 20 10 10 3F 2A 14 63 BE D7 EF A7 3C DE E5 08 3F 1D CE C9 "
    "40 20 0C C1 F2 46 C3 C1 EC E0 76 C2 8F 85 3F 40 10 0C BD 93 2C CC BD 92 0A 16 BE 3A 6E EC 40 "
    "30 0C 42 51 94 64 C2 7B 5A 5A C1 CC C0 AE 80 20 0C 40 85 4D 6D C1 25 55 9E C0 90 8E 1F 80 30 "
    "10 3F 7F F8 98 3B AA 9E E5 BC 53 9E C0 BB B9 06 0C C0 20 0C 3E DC 74 39 BE 75 2B 48 3F AF 9A "
    "3F 30 10 04 00 01 86 DE E0 20 04 00 48 14 01";
// Orientation only (no inertial data).
const char* const kGolden6 =
    "10 20 02 46 82 10 60 04 01 C4 FC 3E 20 10 10 3F 71 CE 6C BE A5 6B CF 3C 61 3B D8 BD 69 1D 25 "
    "E0 20 04 00 40 00 03";

std::vector<std::byte> bytes_of(const std::vector<std::uint8_t>& v) {
  std::vector<std::byte> out(v.size());
  std::memcpy(out.data(), v.data(), v.size());
  return out;
}

std::vector<ImuSample> feed(XsensMtData2Decoder& dec, const std::vector<std::uint8_t>& stream,
                            std::size_t chunk = SIZE_MAX, std::int64_t rx = 0) {
  std::vector<ImuSample> out;
  const auto b = bytes_of(stream);
  for (std::size_t i = 0; i < b.size(); i += chunk) {
    const std::size_t n = std::min(chunk, b.size() - i);
    dec.on_bytes({b.data() + i, n}, rx + static_cast<std::int64_t>(i),
                 [&](const ImuSample& s) { out.push_back(s); });
  }
  return out;
}

TEST(XsensMtData2, RealMti300MessagesDecodeToMtManagersValues) {
  XsensMtData2Decoder dec;
  std::vector<std::uint8_t> stream;
  for (const char* g : {kGolden1, kGolden3, kGolden5, kGolden6}) {
    const auto m = encode_xbus_message(0x36, hex(g));
    stream.insert(stream.end(), m.begin(), m.end());
  }
  // The first message is 139 data bytes: LEN 0x8B, and its checksum closes the sum to 0.
  const auto first = encode_xbus_message(0x36, hex(kGolden1));
  EXPECT_EQ(first[3], 0x8B);
  EXPECT_EQ(first.size(), 139u + 5u);

  const auto samples = feed(dec, stream, SIZE_MAX, 7);
  ASSERT_EQ(samples.size(), 3u);  // the orientation-only message is not an IMU sample
  constexpr double kTol = 1e-7;   // MT Manager prints 8 decimals
  EXPECT_NEAR(samples[0].accel_m_s2.x(), -0.07915300, kTol);
  EXPECT_NEAR(samples[0].accel_m_s2.y(), -0.16655955, kTol);
  EXPECT_NEAR(samples[0].accel_m_s2.z(), 9.82217598, 1e-6);
  EXPECT_NEAR(samples[0].gyro_rad_s.x(), -0.00541657, kTol);
  EXPECT_NEAR(samples[0].gyro_rad_s.y(), -0.00458360, kTol);
  EXPECT_NEAR(samples[0].gyro_rad_s.z(), 0.00792891, kTol);
  EXPECT_EQ(samples[0].stamp.sensor.ns, 5719854LL * 100'000);  // SampleTimeFine x 100 us
  EXPECT_EQ(samples[0].stamp.host.ns, 7);
  EXPECT_NEAR(samples[1].accel_m_s2.z(), 9.81525326, 1e-6);
  EXPECT_NEAR(samples[1].gyro_rad_s.y(), -0.00810772, kTol);
  EXPECT_EQ(samples[1].stamp.sensor.ns, 5561329LL * 100'000);
  EXPECT_NEAR(samples[2].accel_m_s2.x(), -30.28455162, 1e-5);
  EXPECT_NEAR(samples[2].accel_m_s2.z(), -71.76024628, 1e-5);
  EXPECT_NEAR(samples[2].gyro_rad_s.y(), -10.33340263, 1e-6);
  EXPECT_EQ(dec.counters().saturated, 1u);  // only the shaken one clips
  EXPECT_EQ(dec.last_status_word(), 0x00400003u);
  EXPECT_EQ(dec.last_packet_counter(), 18050);
  EXPECT_EQ(dec.counters().frames, 4u);
  EXPECT_EQ(dec.counters().checksum_errors, 0u);
  EXPECT_EQ(dec.counters().malformed, 0u);
  // Counters 42581 -> 36240 -> 64389 -> 18050 are excerpts from different times: a step of more
  // than half the 16-bit range backwards is a restart (nothing counted); forward steps, across
  // the wrap too, count the messages in between.
  EXPECT_EQ(dec.counters().sequence_gaps, (64389u - 36240u - 1u) + (18050u + 65536u - 64389u - 1u));
}

TEST(XsensMtData2, EverySplitPointOfAStreamDecodesTheSameSamples) {
  std::vector<std::uint8_t> stream;
  for (int k = 0; k < 6; ++k) {
    XsensSample s;
    s.packet_counter = static_cast<std::uint16_t>(100 + k);
    s.sample_time_fine = static_cast<std::uint32_t>(1000 + 25 * k);  // 400 Hz
    s.accel_m_s2 = Eigen::Vector3d(0.1 * k, -0.2, 9.81);
    s.gyro_rad_s = Eigen::Vector3d(0.01, 0.02 * k, -0.03);
    s.precision = static_cast<XsensPrecision>(k % 4);
    const auto m = encode_mtdata2_sample(s);
    stream.insert(stream.end(), m.begin(), m.end());
  }
  XsensMtData2Decoder whole;
  const auto reference = feed(whole, stream);
  ASSERT_EQ(reference.size(), 6u);
  for (std::size_t chunk = 1; chunk <= stream.size(); ++chunk) {
    XsensMtData2Decoder dec;
    const auto got = feed(dec, stream, chunk);
    ASSERT_EQ(got.size(), reference.size()) << "chunk " << chunk;
    for (std::size_t i = 0; i < got.size(); ++i) {
      EXPECT_EQ(got[i].accel_m_s2, reference[i].accel_m_s2);
      EXPECT_EQ(got[i].stamp.sensor, reference[i].stamp.sensor);
    }
    EXPECT_EQ(dec.counters().skipped_bytes, 0u);
  }
  // Each precision round-trips within its resolution.
  for (std::size_t k = 0; k < reference.size(); ++k) {
    const double tol = (k % 4 == 1) ? 1.0 / 1048576.0 : (k % 4 == 0 ? 1e-6 : 1e-9);
    EXPECT_NEAR(reference[k].accel_m_s2.x(), 0.1 * static_cast<double>(k), tol) << k;
    EXPECT_NEAR(reference[k].gyro_rad_s.y(), 0.02 * static_cast<double>(k), tol) << k;
    EXPECT_EQ(reference[k].stamp.sensor.ns, (1000 + 25 * static_cast<std::int64_t>(k)) * 100'000);
  }
}

TEST(XsensMtData2, CorruptionIsCountedAndTheStreamResynchronises) {
  std::mt19937 rng(3);
  std::vector<std::vector<std::uint8_t>> messages;
  for (int k = 0; k < 200; ++k) {
    XsensSample s;
    s.packet_counter = static_cast<std::uint16_t>(65500 + k);               // wraps at 65536
    s.sample_time_fine = 0xFFFFFF00U + static_cast<std::uint32_t>(10 * k);  // wraps at 2^32
    s.accel_m_s2 = Eigen::Vector3d(k, 0, 0);
    messages.push_back(encode_mtdata2_sample(s));
  }
  std::vector<std::uint8_t> stream{0x00, 0xFA, 0x13};  // leading garbage with a false preamble
  std::size_t corrupted = 0;
  std::size_t dropped = 0;
  std::vector<double> expected;
  for (std::size_t k = 0; k < messages.size(); ++k) {
    auto m = messages[k];
    if (k % 17 == 5) {  // flip one data byte: checksum error
      m[6 + rng() % (m.size() - 8)] ^= 0x40;
      ++corrupted;
    } else if (k % 23 == 7) {  // lost on the wire: a counter gap
      ++dropped;
      continue;
    } else {
      expected.push_back(static_cast<double>(k));
    }
    stream.insert(stream.end(), m.begin(), m.end());
    // An acknowledgement between samples (another message id): skipped, not an error.
    if (k == 50) {
      const auto ack = encode_xbus_message(0x11, {});
      stream.insert(stream.end(), ack.begin(), ack.end());
    }
  }
  XsensMtData2Decoder dec;
  const auto got = feed(dec, stream, 37);
  ASSERT_EQ(got.size(), expected.size());
  for (std::size_t i = 0; i < got.size(); ++i) EXPECT_EQ(got[i].accel_m_s2.x(), expected[i]);
  EXPECT_GE(dec.counters().checksum_errors, corrupted);  // plus false preambles inside them
  EXPECT_EQ(dec.counters().sequence_gaps, corrupted + dropped);
  EXPECT_EQ(dec.counters().counter_wraps, 1u);
  EXPECT_EQ(dec.other_messages(), 1u);
  // Sensor time keeps increasing across the 32-bit wrap.
  for (std::size_t i = 1; i < got.size(); ++i)
    EXPECT_GT(got[i].stamp.sensor, got[i - 1].stamp.sensor);
}

TEST(XsensMtData2, MalformedItemsAndExtendedLengths) {
  XsensMtData2Decoder dec;
  // An item claiming more bytes than the message holds.
  const auto bad = encode_xbus_message(0x36, std::vector<std::uint8_t>{0x40, 0x20, 0x0C, 0x00});
  // Acceleration with a size that does not fit float32 x 3.
  const auto odd = encode_xbus_message(
      0x36, std::vector<std::uint8_t>{0x40, 0x20, 0x08, 0, 0, 0, 0, 0, 0, 0, 0});
  // A sample without SampleTimeFine cannot be stamped: incomplete.
  std::vector<std::uint8_t> no_time{0x40, 0x20, 0x0C};
  no_time.resize(15, 0);
  no_time.insert(no_time.end(), {0x80, 0x20, 0x0C});
  no_time.resize(30, 0);
  const auto untimed = encode_xbus_message(0x36, no_time);
  // A long message (extended length) with padding items the decoder skips.
  XsensSample s;
  s.sample_time_fine = 77;
  auto base = encode_mtdata2_sample(s);
  std::vector<std::uint8_t> data(base.begin() + 4, base.end() - 1);
  for (int i = 0; i < 30; ++i)
    data.insert(data.end(), {0xC0, 0x20, 0x0C, 1, 2, 3, 4, 5, 6, 7, 8, 9, 10, 11, 12});
  const auto extended = encode_xbus_message(0x36, data);
  ASSERT_EQ(extended[3], 0xFF);
  std::vector<std::uint8_t> stream;
  for (const auto* m : {&bad, &odd, &untimed, &extended})
    stream.insert(stream.end(), m->begin(), m->end());
  const auto got = feed(dec, stream, 5);
  ASSERT_EQ(got.size(), 1u);
  EXPECT_EQ(got[0].stamp.sensor.ns, 77 * 100'000);
  EXPECT_EQ(dec.counters().malformed, 2u);
  EXPECT_EQ(dec.counters().incomplete, 1u);
}

}  // namespace
}  // namespace livod::imu
