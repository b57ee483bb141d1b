#include "drivers/imu/vectornav_binary.hpp"

#include <gtest/gtest.h>

#include <bit>
#include <cstring>
#include <random>
#include <vector>

namespace livod::imu {
namespace {

// A binary output packet recorded from a real VN-100 (published as a unit-test vector by a public
// satellite on-board-computer project; the bytes are a test vector, not code): Common group with
// YawPitchRoll, AngularRate, Accel and MagPres (group field 0x0528), 56 payload bytes, CRC C0 E9.
// The sensor lies pitched up 88 degrees, so gravity is along +x.
const std::vector<std::uint8_t> kRealVn100Header = {0xFA, 0x01, 0x28, 0x05};
const std::vector<std::uint8_t> kRealVn100Payload = {
    0xA8, 0x02, 0xC3, 0x3F, 0xE7, 0x89, 0xB0, 0x42, 0x3D, 0xA9, 0x6A, 0xC1, 0xD0, 0x83,
    0x54, 0x3A, 0x92, 0x3E, 0x0B, 0xBB, 0x1C, 0x25, 0x30, 0xBA, 0x04, 0x7D, 0x1C, 0x41,
    0x3B, 0xB2, 0x83, 0x3D, 0x4E, 0xEA, 0x9C, 0xBE, 0xF1, 0xBD, 0x93, 0xBE, 0xA4, 0x55,
    0x8C, 0xBD, 0x26, 0xC7, 0x77, 0x3E, 0xF4, 0x28, 0xE6, 0x41, 0x57, 0xCE, 0xC1, 0x42};
const std::vector<std::uint8_t> kRealVn100Crc = {0xC0, 0xE9};

std::vector<std::uint8_t> real_vn100_packet() {
  std::vector<std::uint8_t> p = kRealVn100Header;
  p.insert(p.end(), kRealVn100Payload.begin(), kRealVn100Payload.end());
  p.insert(p.end(), kRealVn100Crc.begin(), kRealVn100Crc.end());
  return p;
}

std::vector<std::byte> bytes_of(const std::vector<std::uint8_t>& v) {
  std::vector<std::byte> out(v.size());
  if (!v.empty()) std::memcpy(out.data(), v.data(), v.size());
  return out;
}

std::vector<ImuSample> feed(VectorNavBinaryDecoder& dec, const std::vector<std::uint8_t>& stream,
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

void append(std::vector<std::uint8_t>& out, const std::vector<std::uint8_t>& more) {
  out.insert(out.end(), more.begin(), more.end());
}

VectorNavSample sample_at(int k) {
  VectorNavSample s;
  s.time_startup_ns = 5'000'000'000ULL + static_cast<std::uint64_t>(k) * 2'500'000ULL;  // 400 Hz
  s.accel_m_s2 = Eigen::Vector3d(0.1 * k, -9.81, 0.25);
  s.gyro_rad_s = Eigen::Vector3d(0.01, -0.002 * k, 0.5);
  return s;
}

TEST(VectorNavBinary, RealVn100PacketChecksAndFrames) {
  const auto packet = real_vn100_packet();
  // CRC-16-CCITT over groups..payload is the transmitted CRC; over everything after sync it is 0.
  EXPECT_EQ(vectornav_crc16({packet.data() + 1, packet.size() - 3}), 0xC0E9);
  EXPECT_EQ(vectornav_crc16({packet.data() + 1, packet.size() - 1}), 0);

  // No TimeStartup: the packet is framed and checked, but the sample has no sensor time.
  VectorNavBinaryDecoder dec;
  EXPECT_TRUE(feed(dec, packet).empty());
  EXPECT_EQ(dec.counters().frames, 1u);
  EXPECT_EQ(dec.counters().checksum_errors, 0u);
  EXPECT_EQ(dec.counters().malformed, 0u);
  EXPECT_EQ(dec.counters().skipped_bytes, 0u);
  EXPECT_EQ(dec.counters().incomplete, 1u);

  // The same fields with TimeStartup (bit 0) in front: the recorded rates and accelerations.
  std::vector<std::uint8_t> payload = {0x40, 0x42, 0x0F, 0, 0, 0, 0, 0};  // 1 000 000 ns
  append(payload, kRealVn100Payload);
  const std::array<std::uint16_t, 1> fields{0x0529};
  VectorNavBinaryDecoder timed;
  const auto samples = feed(timed, encode_vectornav_packet(0x01, fields, payload), SIZE_MAX, 77);
  ASSERT_EQ(samples.size(), 1u);
  EXPECT_EQ(samples[0].stamp.sensor.ns, 1'000'000);
  EXPECT_EQ(samples[0].stamp.host.ns, 77);
  EXPECT_NEAR(samples[0].gyro_rad_s.x(), 0.000810679979622364, 1e-12);
  EXPECT_NEAR(samples[0].gyro_rad_s.y(), -0.0021247011609375477, 1e-12);
  EXPECT_NEAR(samples[0].gyro_rad_s.z(), -0.0006719396915286779, 1e-12);
  EXPECT_NEAR(samples[0].accel_m_s2.x(), 9.780521392822266, 1e-9);
  EXPECT_NEAR(samples[0].accel_m_s2.y(), 0.06430479139089584, 1e-9);
  EXPECT_NEAR(samples[0].accel_m_s2.z(), -0.30647510290145874, 1e-9);
  EXPECT_NEAR(samples[0].accel_m_s2.norm(), 9.79, 0.02);  // gravity, at rest
}

TEST(VectorNavBinary, EncodedSamplesRoundTrip) {
  for (const bool uncompensated : {false, true}) {
    VectorNavSample s = sample_at(3);
    s.uncompensated = uncompensated;
    const auto packet = encode_vectornav_sample(s);
    EXPECT_EQ(packet.size(), uncompensated ? 1 + 1 + 2 + 8 + 24 + 2 : 1 + 1 + 4 + 8 + 24 + 2 + 2);
    VectorNavBinaryDecoder dec;
    const auto out = feed(dec, packet);
    ASSERT_EQ(out.size(), 1u);
    EXPECT_EQ(out[0].stamp.sensor.ns, static_cast<std::int64_t>(s.time_startup_ns));
    EXPECT_LE((out[0].accel_m_s2 - s.accel_m_s2).cwiseAbs().maxCoeff(), 1e-6);
    EXPECT_LE((out[0].gyro_rad_s - s.gyro_rad_s).cwiseAbs().maxCoeff(), 1e-7);
    EXPECT_EQ(dec.counters().samples, 1u);
    EXPECT_EQ(dec.counters().bytes, packet.size());
  }
}

TEST(VectorNavBinary, EverySplitPointOfAStreamDecodesTheSameSamples) {
  std::vector<std::uint8_t> stream = {0x24, 0x56, 0x4E};  // the tail of an ASCII reply
  for (int k = 0; k < 6; ++k) append(stream, encode_vectornav_sample(sample_at(k)));
  append(stream, real_vn100_packet());  // no TimeStartup: incomplete
  append(stream, encode_vectornav_sample(sample_at(6)));
  VectorNavBinaryDecoder whole;
  const auto reference = feed(whole, stream);
  ASSERT_EQ(reference.size(), 7u);
  EXPECT_EQ(whole.counters().incomplete, 1u);
  EXPECT_EQ(whole.counters().skipped_bytes, 3u);
  for (std::size_t chunk = 1; chunk <= stream.size(); ++chunk) {
    VectorNavBinaryDecoder dec;
    const auto out = feed(dec, stream, chunk);
    ASSERT_EQ(out.size(), reference.size()) << "chunk " << chunk;
    for (std::size_t i = 0; i < out.size(); ++i) {
      EXPECT_EQ(out[i].stamp.sensor.ns, reference[i].stamp.sensor.ns);
      EXPECT_EQ(out[i].accel_m_s2, reference[i].accel_m_s2);
      EXPECT_EQ(out[i].gyro_rad_s, reference[i].gyro_rad_s);
    }
    // The sample takes the receive time of the read that completed it.
    EXPECT_GE(out.back().stamp.host.ns,
              static_cast<std::int64_t>(stream.size()) - static_cast<std::int64_t>(chunk));
    EXPECT_EQ(dec.counters().frames, whole.counters().frames);
  }
}

TEST(VectorNavBinary, CorruptionIsCountedAndTheStreamResynchronises) {
  std::mt19937 rng(7);
  std::vector<std::uint8_t> stream;
  int corrupted = 0;
  for (int k = 0; k < 200; ++k) {
    auto p = encode_vectornav_sample(sample_at(k));
    if (k % 10 == 5) {
      // One flipped bit anywhere after the sync byte: CRC-16 catches every single-bit error.
      p[1 + rng() % (p.size() - 1)] ^= static_cast<std::uint8_t>(1U << (rng() % 8));
      ++corrupted;
    }
    if (k % 7 == 3) {
      // Line noise with a false sync byte in it.
      append(stream, {0xFA, 0x01, 0x21, 0x01, 0x33});
    }
    append(stream, p);
  }
  for (const std::size_t chunk : {std::size_t{1}, std::size_t{13}, std::size_t{64}, SIZE_MAX}) {
    VectorNavBinaryDecoder dec;
    const auto out = feed(dec, stream, chunk);
    EXPECT_EQ(out.size(), 200u - static_cast<std::size_t>(corrupted)) << chunk;
    // Every lost packet shows as a gap in TimeStartup.
    EXPECT_EQ(dec.counters().sequence_gaps, static_cast<std::uint64_t>(corrupted)) << chunk;
    EXPECT_GE(dec.counters().checksum_errors + dec.counters().malformed,
              static_cast<std::uint64_t>(corrupted));
    EXPECT_GT(dec.counters().skipped_bytes, 0u);
    for (std::size_t i = 1; i < out.size(); ++i) {
      EXPECT_GT(out[i].stamp.sensor.ns, out[i - 1].stamp.sensor.ns);
    }
  }
}

TEST(VectorNavBinary, PacketsThatCannotBeFramedAreMalformedAndSkipped) {
  const std::vector<std::uint8_t> good = encode_vectornav_sample(sample_at(0));
  const std::array<std::uint16_t, 1> reserved{0x8001};  // Common bit 15: no known size
  const std::array<std::uint16_t, 1> none{0x0000};      // a selected group without fields
  const std::vector<std::uint8_t> payload(16, 0);
  for (const auto& bad : {
           encode_vectornav_packet(0x80, {}, payload),        // groups 8+: extension byte
           encode_vectornav_packet(0x00, {}, payload),        // no group
           encode_vectornav_packet(0x01, reserved, payload),  // unknown field size
           encode_vectornav_packet(0x01, none, payload),
       }) {
    std::vector<std::uint8_t> stream = bad;
    append(stream, good);
    VectorNavBinaryDecoder dec;
    const auto out = feed(dec, stream, 5);
    EXPECT_EQ(out.size(), 1u);
    EXPECT_GE(dec.counters().malformed, 1u);
    EXPECT_EQ(dec.counters().samples, 1u);
  }
  // A truncated packet followed by a complete one: the CRC over the wrong bytes fails, the decoder
  // goes back to the byte after the false sync and finds the next packet.
  std::vector<std::uint8_t> torn(good.begin(), good.begin() + 20);
  append(torn, encode_vectornav_sample(sample_at(1)));
  VectorNavBinaryDecoder dec;
  const auto out = feed(dec, torn, 3);
  ASSERT_EQ(out.size(), 1u);
  EXPECT_EQ(out[0].stamp.sensor.ns, static_cast<std::int64_t>(sample_at(1).time_startup_ns));
  EXPECT_EQ(dec.counters().checksum_errors, 1u);
}

// Builds a packet from (group, field bit, value bytes) in the order the protocol lays them out.
struct Field {
  int group;
  int bit;
  std::vector<std::uint8_t> value;
};

std::vector<std::uint8_t> packet_of(const std::vector<Field>& fields) {
  std::uint8_t groups = 0;
  std::array<std::uint16_t, 7> words{};
  for (const auto& f : fields) {
    groups = static_cast<std::uint8_t>(groups | (1U << f.group));
    words[static_cast<std::size_t>(f.group)] =
        static_cast<std::uint16_t>(words[static_cast<std::size_t>(f.group)] | (1U << f.bit));
  }
  std::vector<std::uint16_t> present;
  for (std::size_t g = 0; g < 7; ++g) {
    if ((groups & (1U << g)) != 0) present.push_back(words[g]);
  }
  std::vector<std::uint8_t> payload;
  for (const auto& f : fields) append(payload, f.value);
  return encode_vectornav_packet(groups, present, payload);
}

std::vector<std::uint8_t> le(std::uint64_t v, int n) {
  std::vector<std::uint8_t> out;
  for (int i = 0; i < n; ++i) out.push_back(static_cast<std::uint8_t>(v >> (8 * i)));
  return out;
}

std::vector<std::uint8_t> vec3(double x, double y, double z) {
  std::vector<std::uint8_t> out;
  for (const double v : {x, y, z})
    append(out, le(std::bit_cast<std::uint32_t>(static_cast<float>(v)), 4));
  return out;
}

TEST(VectorNavBinary, FieldsFromEveryGroupAndTheirPrecedence) {
  // Time group TimeStartup and SyncInCnt, IMU group uncompensated and compensated outputs,
  // SensSat with the gyro z flag, and an Attitude group field between them to skip.
  const auto packet = packet_of({
      {1, 0, le(42'000'000, 8)},                    // Time.TimeStartup
      {1, 7, le(9, 4)},                             // Time.SyncInCnt
      {2, 2, vec3(1, 2, 3)},                        // IMU.UncompAccel
      {2, 3, vec3(0.1, 0.2, 0.3)},                  // IMU.UncompGyro
      {2, 9, vec3(4, 5, 6)},                        // IMU.Accel (compensated: wins)
      {2, 10, vec3(0.4, 0.5, 0.6)},                 // IMU.AngularRate (compensated: wins)
      {2, 11, le(0x0100, 2)},                       // IMU.SensSat: gyro z saturated
      {4, 3, std::vector<std::uint8_t>(36, 0x11)},  // Attitude.DCM
  });
  VectorNavBinaryDecoder dec;
  const auto out = feed(dec, packet);
  ASSERT_EQ(out.size(), 1u);
  EXPECT_EQ(out[0].stamp.sensor.ns, 42'000'000);
  EXPECT_EQ(out[0].accel_m_s2, Eigen::Vector3d(4, 5, 6));
  EXPECT_NEAR((out[0].gyro_rad_s - Eigen::Vector3d(0.4, 0.5, 0.6)).norm(), 0.0, 1e-7);
  EXPECT_EQ(dec.counters().saturated, 1u);
  EXPECT_EQ(dec.last_saturation(), 0x0100);
  ASSERT_TRUE(dec.last_sync_in());
  EXPECT_EQ(dec.last_sync_in()->count, 9u);

  // Uncompensated only: taken.
  const auto uncomp = packet_of({{0, 0, le(1, 8)}, {2, 2, vec3(1, 2, 3)}, {2, 3, vec3(7, 8, 9)}});
  VectorNavBinaryDecoder dec2;
  const auto out2 = feed(dec2, uncomp);
  ASSERT_EQ(out2.size(), 1u);
  EXPECT_EQ(out2[0].accel_m_s2, Eigen::Vector3d(1, 2, 3));
  EXPECT_EQ(out2[0].gyro_rad_s, Eigen::Vector3d(7, 8, 9));

  // Accel without a rate: incomplete; attitude only: another packet, not a sample.
  VectorNavBinaryDecoder dec3;
  EXPECT_TRUE(feed(dec3, packet_of({{0, 0, le(1, 8)}, {0, 8, vec3(0, 0, 9.8)}})).empty());
  EXPECT_EQ(dec3.counters().incomplete, 1u);
  EXPECT_TRUE(feed(dec3, packet_of({{0, 0, le(1, 8)}, {0, 3, vec3(10, 20, 30)}})).empty());
  EXPECT_EQ(dec3.other_packets(), 1u);
  EXPECT_EQ(dec3.counters().frames, 2u);

  // A NaN rate or a TimeStartup past int64: malformed, dropped.
  VectorNavBinaryDecoder dec4;
  const double nan = std::numeric_limits<double>::quiet_NaN();
  EXPECT_TRUE(
      feed(dec4, packet_of({{0, 0, le(1, 8)}, {0, 5, vec3(nan, 0, 0)}, {0, 8, vec3(0, 0, 9.8)}}))
          .empty());
  EXPECT_TRUE(
      feed(dec4, packet_of({{0, 0, le(~0ULL, 8)}, {0, 5, vec3(0, 0, 0)}, {0, 8, vec3(0, 0, 9.8)}}))
          .empty());
  EXPECT_EQ(dec4.counters().malformed, 2u);
}

TEST(VectorNavBinary, GapsFromTimeStartupStepsAndRestarts) {
  std::vector<std::uint8_t> stream;
  for (const int k : {0, 1, 2, 5, 6, 9}) append(stream, encode_vectornav_sample(sample_at(k)));
  // The sensor restarts: TimeStartup goes back; not a gap.
  VectorNavSample restarted = sample_at(0);
  restarted.time_startup_ns = 1'000'000;
  append(stream, encode_vectornav_sample(restarted));
  restarted.time_startup_ns += 2'500'000;
  append(stream, encode_vectornav_sample(restarted));
  VectorNavBinaryDecoder dec;
  EXPECT_EQ(feed(dec, stream).size(), 8u);
  EXPECT_EQ(dec.counters().sequence_gaps, 4u);  // 3, 4, 7, 8
}

}  // namespace
}  // namespace livod::imu
