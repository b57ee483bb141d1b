#include "drivers/imu/vectornav_binary.hpp"

#include <bit>
#include <cstring>
#include <limits>

namespace livod::imu {
namespace {

constexpr std::uint8_t kSync = 0xFA;
constexpr std::size_t kGroupCount = kVectorNavFieldBytes.size();  // groups 1-7
constexpr std::uint8_t kGroupsKnownMask = 0x7F;                   // bit 7: extension byte

// Group indices (bit offsets in the groups byte).
constexpr int kCommon = 0;
constexpr int kTime = 1;
constexpr int kImu = 2;

// Field bits.
constexpr int kCommonTimeStartup = 0;
constexpr int kCommonTimeSyncIn = 2;
constexpr int kCommonAngularRate = 5;
constexpr int kCommonAccel = 8;
constexpr int kCommonImu = 9;
constexpr int kCommonSyncInCnt = 13;
constexpr int kTimeTimeStartup = 0;
constexpr int kTimeTimeSyncIn = 4;
constexpr int kTimeSyncInCnt = 7;
constexpr int kImuUncompAccel = 2;
constexpr int kImuUncompGyro = 3;
constexpr int kImuAccel = 9;
constexpr int kImuAngularRate = 10;
constexpr int kImuSensSat = 11;

constexpr std::uint16_t kSatAccelGyro = 0x01F8;  // SensSat bits 3-8

std::uint16_t le16(const std::uint8_t* p) {
  return static_cast<std::uint16_t>(p[0] | (p[1] << 8));
}
std::uint32_t le32(const std::uint8_t* p) {
  return static_cast<std::uint32_t>(p[0]) | (static_cast<std::uint32_t>(p[1]) << 8) |
         (static_cast<std::uint32_t>(p[2]) << 16) | (static_cast<std::uint32_t>(p[3]) << 24);
}
std::uint64_t le64(const std::uint8_t* p) {
  return static_cast<std::uint64_t>(le32(p)) | (static_cast<std::uint64_t>(le32(p + 4)) << 32);
}
Eigen::Vector3d vec3f(const std::uint8_t* p) {
  return {static_cast<double>(std::bit_cast<float>(le32(p))),
          static_cast<double>(std::bit_cast<float>(le32(p + 4))),
          static_cast<double>(std::bit_cast<float>(le32(p + 8)))};
}

void put_le(std::vector<std::uint8_t>& out, std::uint64_t v, int bytes) {
  for (int i = 0; i < bytes; ++i) out.push_back(static_cast<std::uint8_t>((v >> (8 * i)) & 0xFF));
}
void put_vec3f(std::vector<std::uint8_t>& out, const Eigen::Vector3d& v) {
  for (int i = 0; i < 3; ++i)
    put_le(out, std::bit_cast<std::uint32_t>(static_cast<float>(v[i])), 4);
}

// CRC-16-CCITT (poly 0x1021, MSB first), one byte at a time: crc = (crc << 8) ^ T[(crc >> 8) ^ b].
constexpr std::array<std::uint16_t, 256> make_crc_table() {
  std::array<std::uint16_t, 256> table{};
  for (unsigned i = 0; i < 256; ++i) {
    auto crc = static_cast<std::uint16_t>(i << 8);
    for (int k = 0; k < 8; ++k) {
      crc = (crc & 0x8000) != 0 ? static_cast<std::uint16_t>((crc << 1) ^ 0x1021)
                                : static_cast<std::uint16_t>(crc << 1);
    }
    table[i] = crc;
  }
  return table;
}
constexpr std::array<std::uint16_t, 256> kCrcTable = make_crc_table();

// One of the accel / gyro readings of a packet, compensated or not.
struct Reading {
  Eigen::Vector3d value = Eigen::Vector3d::Zero();
  bool have = false;
  bool compensated = false;

  void offer(const Eigen::Vector3d& v, bool is_compensated) {
    if (have && compensated && !is_compensated) return;  // the compensated output wins
    value = v;
    have = true;
    compensated = is_compensated;
  }
};

}  // namespace

std::uint16_t vectornav_crc16(std::span<const std::uint8_t> bytes) {
  std::uint16_t crc = 0;
  for (const std::uint8_t b : bytes) {
    crc = static_cast<std::uint16_t>((crc << 8) ^ kCrcTable[((crc >> 8) ^ b) & 0xFF]);
  }
  return crc;
}

void VectorNavBinaryDecoder::on_bytes(std::span<const std::byte> bytes, std::int64_t rx_time_ns,
                                      const ImuSink& sink) {
  counters_.bytes += bytes.size();
  std::size_t i = 0;
  while (i < bytes.size()) {
    const std::size_t n = std::min(bytes.size() - i, buf_.size() - size_);
    std::memcpy(buf_.data() + size_, bytes.data() + i, n);
    size_ += n;
    i += n;
    drain(rx_time_ns, sink);
  }
}

std::optional<std::size_t> VectorNavBinaryDecoder::packet_size(std::size_t pos) const {
  const std::size_t avail = size_ - pos;
  if (avail < 2) return 0;
  const std::uint8_t groups = buf_[pos + 1];
  if (groups == 0 || (groups & ~kGroupsKnownMask) != 0) return std::nullopt;
  const auto n_groups = static_cast<std::size_t>(std::popcount(groups));
  const std::size_t header = 2 + 2 * n_groups;
  if (avail < header) return 0;
  std::size_t payload = 0;
  std::size_t word = pos + 2;
  for (std::size_t g = 0; g < kGroupCount; ++g) {
    if ((groups & (1U << g)) == 0) continue;
    const std::uint16_t fields = le16(&buf_[word]);
    word += 2;
    if (fields == 0) return std::nullopt;  // a selected group without fields: not a real header
    for (std::size_t b = 0; b < 16; ++b) {
      if ((fields & (1U << b)) == 0) continue;
      const std::uint8_t bytes = kVectorNavFieldBytes[g][b];
      if (bytes == 0) return std::nullopt;  // reserved / extension / unknown size: cannot frame
      payload += bytes;
    }
  }
  return header + payload + 2;
}

void VectorNavBinaryDecoder::drain(std::int64_t rx_time_ns, const ImuSink& sink) {
  std::size_t pos = 0;
  while (pos < size_) {
    if (buf_[pos] != kSync) {
      ++pos;
      ++counters_.skipped_bytes;
      continue;
    }
    const auto total = packet_size(pos);
    if (!total) {
      ++counters_.malformed;
      ++pos;
      ++counters_.skipped_bytes;
      continue;
    }
    if (*total == 0 || size_ - pos < *total) break;  // wait for the rest
    if (vectornav_crc16({&buf_[pos + 1], *total - 1}) != 0) {
      // Corrupted, or a 0xFA inside another packet's payload: resynchronise from the next byte.
      ++counters_.checksum_errors;
      ++pos;
      ++counters_.skipped_bytes;
      continue;
    }
    ++counters_.frames;
    handle_packet(pos, rx_time_ns, sink);
    pos += *total;
  }
  if (pos > 0) {
    std::memmove(buf_.data(), buf_.data() + pos, size_ - pos);
    size_ -= pos;
  }
  if (size_ == buf_.size()) {
    // Cannot happen with a well-formed stream (the buffer holds the largest packet); drop a byte
    // so that parsing moves on.
    std::memmove(buf_.data(), buf_.data() + 1, size_ - 1);
    --size_;
    ++counters_.skipped_bytes;
  }
}

void VectorNavBinaryDecoder::handle_packet(std::size_t pos, std::int64_t rx_time_ns,
                                           const ImuSink& sink) {
  const std::uint8_t groups = buf_[pos + 1];
  const auto n_groups = static_cast<std::size_t>(std::popcount(groups));
  std::size_t word = pos + 2;
  std::size_t p = pos + 2 + 2 * n_groups;  // payload cursor

  std::optional<std::uint64_t> time_startup;
  std::optional<std::uint32_t> sync_in_count;
  std::uint64_t time_sync_in = 0;
  std::optional<std::uint16_t> sens_sat;
  Reading accel;
  Reading gyro;
  for (std::size_t g = 0; g < kGroupCount; ++g) {
    if ((groups & (1U << g)) == 0) continue;
    const std::uint16_t fields = le16(&buf_[word]);
    word += 2;
    for (std::size_t b = 0; b < 16; ++b) {
      if ((fields & (1U << b)) == 0) continue;
      const std::uint8_t* v = &buf_[p];
      p += kVectorNavFieldBytes[g][b];
      const auto bit = static_cast<int>(b);
      if (g == kCommon) {
        if (bit == kCommonTimeStartup) time_startup = le64(v);
        if (bit == kCommonTimeSyncIn) time_sync_in = le64(v);
        if (bit == kCommonSyncInCnt) sync_in_count = le32(v);
        if (bit == kCommonAngularRate) gyro.offer(vec3f(v), true);
        if (bit == kCommonAccel) accel.offer(vec3f(v), true);
        if (bit == kCommonImu) {
          accel.offer(vec3f(v), false);
          gyro.offer(vec3f(v + 12), false);
        }
      } else if (g == kTime) {
        if (bit == kTimeTimeStartup) time_startup = le64(v);
        if (bit == kTimeTimeSyncIn) time_sync_in = le64(v);
        if (bit == kTimeSyncInCnt) sync_in_count = le32(v);
      } else if (g == kImu) {
        if (bit == kImuUncompAccel) accel.offer(vec3f(v), false);
        if (bit == kImuUncompGyro) gyro.offer(vec3f(v), false);
        if (bit == kImuAccel) accel.offer(vec3f(v), true);
        if (bit == kImuAngularRate) gyro.offer(vec3f(v), true);
        if (bit == kImuSensSat) sens_sat = le16(v);
      }
    }
  }

  if (sync_in_count) sync_in_ = SyncIn{*sync_in_count, time_sync_in};
  if (sens_sat) sens_sat_ = *sens_sat;
  if (!accel.have && !gyro.have) {
    ++other_packets_;
    return;
  }
  if (!accel.have || !gyro.have || !time_startup) {
    ++counters_.incomplete;
    return;
  }
  if (!accel.value.allFinite() || !gyro.value.allFinite() ||
      *time_startup > static_cast<std::uint64_t>(std::numeric_limits<std::int64_t>::max())) {
    ++counters_.malformed;
    return;
  }
  if (have_time_) {
    if (*time_startup > last_time_ns_) {
      const std::uint64_t step = *time_startup - last_time_ns_;
      // Steps are whole output periods of the sensor's clock: the smallest one is the period.
      if (period_ns_ == 0 || step < period_ns_) period_ns_ = step;
      if (step > period_ns_ + period_ns_ / 2) {
        counters_.sequence_gaps += (step + period_ns_ / 2) / period_ns_ - 1;
      }
    }
    // A step back is a restart of the sensor (not a gap); an equal stamp is a repeat.
  }
  have_time_ = true;
  last_time_ns_ = *time_startup;
  if (sens_sat && (*sens_sat & kSatAccelGyro) != 0) ++counters_.saturated;

  ImuSample sample;
  sample.stamp.sensor = SensorTime(static_cast<std::int64_t>(*time_startup));
  sample.stamp.host = HostTime(rx_time_ns);
  sample.accel_m_s2 = accel.value;
  sample.gyro_rad_s = gyro.value;
  ++counters_.samples;
  if (sink) sink(sample);
}

std::vector<std::uint8_t> encode_vectornav_packet(std::uint8_t groups,
                                                  std::span<const std::uint16_t> group_fields,
                                                  std::span<const std::uint8_t> payload) {
  std::vector<std::uint8_t> out;
  out.reserve(4 + 2 * group_fields.size() + payload.size());
  out.push_back(kSync);
  out.push_back(groups);
  for (const std::uint16_t f : group_fields) put_le(out, f, 2);
  out.insert(out.end(), payload.begin(), payload.end());
  const std::uint16_t crc = vectornav_crc16({out.data() + 1, out.size() - 1});
  out.push_back(static_cast<std::uint8_t>(crc >> 8));
  out.push_back(static_cast<std::uint8_t>(crc & 0xFF));
  return out;
}

std::vector<std::uint8_t> encode_vectornav_sample(const VectorNavSample& s) {
  std::vector<std::uint8_t> payload;
  if (s.uncompensated) {
    const std::array<std::uint16_t, 1> fields{
        static_cast<std::uint16_t>((1U << kCommonTimeStartup) | (1U << kCommonImu))};
    put_le(payload, s.time_startup_ns, 8);
    put_vec3f(payload, s.accel_m_s2);
    put_vec3f(payload, s.gyro_rad_s);
    return encode_vectornav_packet(1U << kCommon, fields, payload);
  }
  const std::array<std::uint16_t, 2> fields{
      static_cast<std::uint16_t>((1U << kCommonTimeStartup) | (1U << kCommonAngularRate) |
                                 (1U << kCommonAccel)),
      static_cast<std::uint16_t>(1U << kImuSensSat)};
  put_le(payload, s.time_startup_ns, 8);
  put_vec3f(payload, s.gyro_rad_s);  // bit 5 before bit 8
  put_vec3f(payload, s.accel_m_s2);
  put_le(payload, s.sens_sat, 2);
  return encode_vectornav_packet(static_cast<std::uint8_t>((1U << kCommon) | (1U << kImu)), fields,
                                 payload);
}

}  // namespace livod::imu
