#include "drivers/livox/packets.hpp"

#include <cmath>

#include "drivers/livox/bytes.hpp"
#include "drivers/livox/crc.hpp"

namespace livod::livox {
namespace {

struct Sdk1Layout {
  std::size_t point_bytes;
  std::size_t points;  // firings per packet
  std::uint8_t echoes;
  bool spherical;
  bool tagged;
};

bool sdk1_layout(std::uint8_t type, Sdk1Layout& out) {
  switch (type) {
    case 0:
      out = {13, 100, 1, false, false};
      return true;
    case 1:
      out = {9, 100, 1, true, false};
      return true;
    case 2:
      out = {14, 96, 1, false, true};
      return true;
    case 3:
      out = {10, 96, 1, true, true};
      return true;
    case 4:
      out = {28, 48, 2, false, true};
      return true;
    case 5:
      out = {16, 48, 2, true, true};
      return true;
    case 6:
      out = {24, 1, 1, false, false};
      return true;
    case 7:
      out = {42, 30, 3, false, true};
      return true;
    case 8:
      out = {22, 30, 3, true, true};
      return true;
    default:
      return false;
  }
}

// Days since 1970-01-01 of a civil date (proleptic Gregorian).
std::int64_t days_from_civil(int y, unsigned m, unsigned d) {
  y -= m <= 2 ? 1 : 0;
  const int era = (y >= 0 ? y : y - 399) / 400;
  const auto yoe = static_cast<unsigned>(y - era * 400);
  const unsigned doy = (153 * (m + (m > 2 ? static_cast<unsigned>(-3) : 9U)) + 2) / 5 + d - 1;
  const unsigned doe = yoe * 365 + yoe / 4 - yoe / 100 + doy;
  return static_cast<std::int64_t>(era) * 146097 + static_cast<std::int64_t>(doe) - 719468;
}

void cartesian_mm(LivoxPoint& p, std::int32_t x, std::int32_t y, std::int32_t z, double unit_m) {
  p.valid = !(x == 0 && y == 0 && z == 0);
  p.x = static_cast<float>(x * unit_m);
  p.y = static_cast<float>(y * unit_m);
  p.z = static_cast<float>(z * unit_m);
}

void spherical(LivoxPoint& p, std::uint32_t depth_mm, std::uint16_t theta, std::uint16_t phi) {
  // theta: zenith angle, phi: azimuth, both 0.01 deg (sensor-protocols.md 1.3).
  const double r = depth_mm * 1e-3;
  const double t = theta * (M_PI / 18000.0);
  const double f = phi * (M_PI / 18000.0);
  p.valid = depth_mm != 0;
  p.x = static_cast<float>(r * std::sin(t) * std::cos(f));
  p.y = static_cast<float>(r * std::sin(t) * std::sin(f));
  p.z = static_cast<float>(r * std::cos(t));
}

void read_imu(std::span<const std::byte> d, std::size_t off, LivoxPacket& out) {
  for (int a = 0; a < 3; ++a) {
    out.gyro_rad_s[a] = read_le<float>(d, off + 4 * static_cast<std::size_t>(a));
    out.accel_m_s2[a] =
        read_le<float>(d, off + 12 + 4 * static_cast<std::size_t>(a)) * kStandardGravity;
  }
}

void append_imu(std::vector<std::byte>& out, const Eigen::Vector3d& gyro,
                const Eigen::Vector3d& accel) {
  for (int a = 0; a < 3; ++a) append_le<float>(out, static_cast<float>(gyro[a]));
  for (int a = 0; a < 3; ++a)
    append_le<float>(out, static_cast<float>(accel[a] / kStandardGravity));
}

std::int32_t to_units(float metres, double unit_m) {
  return static_cast<std::int32_t>(std::lround(static_cast<double>(metres) / unit_m));
}

}  // namespace

const char* to_string(DecodeError e) {
  switch (e) {
    case DecodeError::kNone:
      return "ok";
    case DecodeError::kTooShort:
      return "payload shorter than its header and points";
    case DecodeError::kUnknownDataType:
      return "unknown data type";
    case DecodeError::kLengthMismatch:
      return "length field inconsistent with the payload";
    case DecodeError::kBadCrc:
      return "CRC-32 mismatch";
    case DecodeError::kBadTime:
      return "invalid timestamp fields";
    case DecodeError::kBadVersion:
      return "not a Livox data packet (version byte)";
  }
  return "unknown";
}

DecodeError decode_sdk1(std::span<const std::byte> d, std::uint32_t point_interval_ns,
                        std::uint8_t lines, LivoxPacket& out) {
  if (d.size() < kSdk1HeaderBytes) return DecodeError::kTooShort;
  if (static_cast<std::uint8_t>(d[0]) != kSdk1Version) return DecodeError::kBadVersion;
  Sdk1Layout layout{};
  out.data_type = static_cast<std::uint8_t>(d[9]);
  if (!sdk1_layout(out.data_type, layout)) return DecodeError::kUnknownDataType;
  // Every SDK1 data type has one fixed datagram length; a longer or shorter one is not SDK1.
  const std::size_t expected = kSdk1HeaderBytes + layout.points * layout.point_bytes;
  if (d.size() < expected) return DecodeError::kTooShort;
  if (d.size() != expected) return DecodeError::kLengthMismatch;
  out.status = read_le<std::uint32_t>(d, 4);
  out.time_type = static_cast<std::uint8_t>(d[8]);
  if (out.time_type == 2 || out.time_type > 4) return DecodeError::kBadTime;  // 2 is reserved
  if (out.time_type == 3) {
    const int year = 2000 + static_cast<int>(d[10]);
    const auto month = static_cast<unsigned>(d[11]);
    const auto day = static_cast<unsigned>(d[12]);
    const auto hour = static_cast<unsigned>(d[13]);
    const auto us = read_le<std::uint32_t>(d, 14);
    if (month < 1 || month > 12 || day < 1 || day > 31 || hour > 23 || us >= 3'600'000'000U) {
      return DecodeError::kBadTime;
    }
    out.timestamp_ns = (days_from_civil(year, month, day) * 86400 + hour * 3600) * 1'000'000'000LL +
                       static_cast<std::int64_t>(us) * 1000;
  } else {
    out.timestamp_ns = static_cast<std::int64_t>(read_le<std::uint64_t>(d, 10));
  }
  out.udp_cnt = 0;
  out.frame_cnt = 0;
  if (out.data_type == 6) {
    out.kind = LivoxPacket::Kind::kImu;
    out.count = 0;
    out.span_ns = 0;
    read_imu(d, kSdk1HeaderBytes, out);
    return DecodeError::kNone;
  }
  out.kind = LivoxPacket::Kind::kPoints;
  out.count = static_cast<std::uint16_t>(layout.points * layout.echoes);
  out.span_ns = static_cast<std::int32_t>((layout.points - 1) * point_interval_ns);
  for (std::size_t f = 0; f < layout.points; ++f) {
    const std::size_t base = kSdk1HeaderBytes + f * layout.point_bytes;
    const auto t = static_cast<std::int32_t>(f * point_interval_ns);
    const auto line = static_cast<std::uint8_t>(lines > 0 ? f % lines : 0);
    for (std::size_t e = 0; e < layout.echoes; ++e) {
      LivoxPoint& p = out.points[f * layout.echoes + e];
      p.t_offset_ns = t;
      p.line = line;
      p.return_index = static_cast<std::uint8_t>(e);
      p.tag = 0;
      if (!layout.spherical) {
        const std::size_t o = base + e * 14;
        cartesian_mm(p, read_le<std::int32_t>(d, o), read_le<std::int32_t>(d, o + 4),
                     read_le<std::int32_t>(d, o + 8), 1e-3);
        p.reflectivity = static_cast<std::uint8_t>(d[o + 12]);
        if (layout.tagged) p.tag = static_cast<std::uint8_t>(d[o + 13]);
      } else if (layout.echoes == 1) {
        spherical(p, read_le<std::uint32_t>(d, base), read_le<std::uint16_t>(d, base + 4),
                  read_le<std::uint16_t>(d, base + 6));
        p.reflectivity = static_cast<std::uint8_t>(d[base + 8]);
        if (layout.tagged) p.tag = static_cast<std::uint8_t>(d[base + 9]);
      } else {
        // theta, phi shared by the echoes, then echoes x (depth u32, refl u8, tag u8)
        const std::size_t o = base + 4 + e * 6;
        spherical(p, read_le<std::uint32_t>(d, o), read_le<std::uint16_t>(d, base),
                  read_le<std::uint16_t>(d, base + 2));
        p.reflectivity = static_cast<std::uint8_t>(d[o + 4]);
        p.tag = static_cast<std::uint8_t>(d[o + 5]);
      }
    }
  }
  return DecodeError::kNone;
}

DecodeError decode_sdk2(std::span<const std::byte> d, std::uint8_t lines, LivoxPacket& out) {
  if (d.size() < kSdk2HeaderBytes) return DecodeError::kTooShort;
  if (static_cast<std::uint8_t>(d[0]) != kSdk2Version) return DecodeError::kBadVersion;
  const auto length = read_le<std::uint16_t>(d, 1);
  if (length != d.size()) return DecodeError::kLengthMismatch;
  const auto interval = read_le<std::uint16_t>(d, 3);
  const auto dot_num = read_le<std::uint16_t>(d, 5);
  out.udp_cnt = read_le<std::uint16_t>(d, 7);
  out.frame_cnt = static_cast<std::uint8_t>(d[9]);
  out.data_type = static_cast<std::uint8_t>(d[10]);
  out.time_type = static_cast<std::uint8_t>(d[11]);
  out.status = 0;
  std::size_t point_bytes = 0;
  switch (out.data_type) {
    case 0:
      point_bytes = 24;
      break;
    case 1:
      point_bytes = 14;
      break;
    case 2:
      point_bytes = 8;
      break;
    case 3:
      point_bytes = 10;
      break;
    default:
      return DecodeError::kUnknownDataType;
  }
  const std::size_t n = out.data_type == 0 ? 1 : dot_num;
  if (n == 0 || n > kMaxPointsPerPacket) return DecodeError::kLengthMismatch;
  if (length != kSdk2HeaderBytes + n * point_bytes) return DecodeError::kLengthMismatch;
  const auto crc = read_le<std::uint32_t>(d, 24);
  if (crc != 0 && crc32_standard(d.subspan(28, length - 28U)) != crc) return DecodeError::kBadCrc;
  out.timestamp_ns = static_cast<std::int64_t>(read_le<std::uint64_t>(d, 28));
  if (out.data_type == 0) {
    out.kind = LivoxPacket::Kind::kImu;
    out.count = 0;
    out.span_ns = 0;
    read_imu(d, kSdk2HeaderBytes, out);
    return DecodeError::kNone;
  }
  out.kind = LivoxPacket::Kind::kPoints;
  out.count = static_cast<std::uint16_t>(n);
  out.span_ns = static_cast<std::int32_t>(interval) * 100;
  for (std::size_t i = 0; i < n; ++i) {
    const std::size_t o = kSdk2HeaderBytes + i * point_bytes;
    LivoxPoint& p = out.points[i];
    // Points are evenly spaced over time_interval (last minus first): divide by n - 1.
    p.t_offset_ns = n > 1 ? static_cast<std::int32_t>(static_cast<std::int64_t>(out.span_ns) *
                                                      static_cast<std::int64_t>(i) /
                                                      static_cast<std::int64_t>(n - 1))
                          : 0;
    p.line = static_cast<std::uint8_t>(lines > 0 ? i % lines : 0);
    p.return_index = 0;
    if (out.data_type == 1) {
      cartesian_mm(p, read_le<std::int32_t>(d, o), read_le<std::int32_t>(d, o + 4),
                   read_le<std::int32_t>(d, o + 8), 1e-3);
      p.reflectivity = static_cast<std::uint8_t>(d[o + 12]);
      p.tag = static_cast<std::uint8_t>(d[o + 13]);
    } else if (out.data_type == 2) {
      cartesian_mm(p, read_le<std::int16_t>(d, o), read_le<std::int16_t>(d, o + 2),
                   read_le<std::int16_t>(d, o + 4), 1e-2);
      p.reflectivity = static_cast<std::uint8_t>(d[o + 6]);
      p.tag = static_cast<std::uint8_t>(d[o + 7]);
    } else {
      spherical(p, read_le<std::uint32_t>(d, o), read_le<std::uint16_t>(d, o + 4),
                read_le<std::uint16_t>(d, o + 6));
      p.reflectivity = static_cast<std::uint8_t>(d[o + 8]);
      p.tag = static_cast<std::uint8_t>(d[o + 9]);
    }
  }
  return DecodeError::kNone;
}

std::vector<std::byte> encode_sdk1_points(const Sdk1Header& h, std::span<const LivoxPoint> points) {
  std::vector<std::byte> out;
  out.reserve(kSdk1HeaderBytes + points.size() * 14);
  out.push_back(std::byte{5});  // packet protocol version
  out.push_back(std::byte{h.slot});
  out.push_back(std::byte{h.lidar_id});
  out.push_back(std::byte{0});
  append_le<std::uint32_t>(out, h.status);
  out.push_back(std::byte{h.timestamp_type});
  out.push_back(std::byte{h.data_type});
  append_le<std::uint64_t>(out, h.timestamp);
  for (const auto& p : points) {
    // One 14-byte record per return; type 4 is just two consecutive records per firing.
    append_le<std::int32_t>(out, p.valid ? to_units(p.x, 1e-3) : 0);
    append_le<std::int32_t>(out, p.valid ? to_units(p.y, 1e-3) : 0);
    append_le<std::int32_t>(out, p.valid ? to_units(p.z, 1e-3) : 0);
    out.push_back(std::byte{p.reflectivity});
    out.push_back(std::byte{p.tag});
  }
  return out;
}

std::vector<std::byte> encode_sdk1_imu(const Sdk1Header& header, const Eigen::Vector3d& gyro,
                                       const Eigen::Vector3d& accel) {
  Sdk1Header h = header;
  h.data_type = 6;
  auto out = encode_sdk1_points(h, {});
  append_imu(out, gyro, accel);
  return out;
}

namespace {

std::vector<std::byte> sdk2_header(const Sdk2Header& h, std::uint16_t dot_num, std::size_t body) {
  std::vector<std::byte> out;
  out.reserve(kSdk2HeaderBytes + body);
  out.push_back(std::byte{0});
  append_le<std::uint16_t>(out, static_cast<std::uint16_t>(kSdk2HeaderBytes + body));
  append_le<std::uint16_t>(out, h.time_interval_100ns);
  append_le<std::uint16_t>(out, dot_num);
  append_le<std::uint16_t>(out, h.udp_cnt);
  out.push_back(std::byte{h.frame_cnt});
  out.push_back(std::byte{h.data_type});
  out.push_back(std::byte{h.time_type});
  out.insert(out.end(), 12, std::byte{0});
  append_le<std::uint32_t>(out, 0);  // CRC, filled in by finish_sdk2
  append_le<std::uint64_t>(out, h.timestamp_ns);
  return out;
}

void finish_sdk2(const Sdk2Header& h, std::vector<std::byte>& out) {
  if (!h.write_crc) return;
  write_le<std::uint32_t>(out, 24, crc32_standard(std::span<const std::byte>(out).subspan(28)));
}

}  // namespace

std::vector<std::byte> encode_sdk2_points(const Sdk2Header& h, std::span<const LivoxPoint> points) {
  const std::size_t point_bytes = h.data_type == 2 ? 8 : 14;
  auto out = sdk2_header(h, static_cast<std::uint16_t>(points.size()), points.size() * point_bytes);
  for (const auto& p : points) {
    if (h.data_type == 2) {
      append_le<std::int16_t>(out, static_cast<std::int16_t>(p.valid ? to_units(p.x, 1e-2) : 0));
      append_le<std::int16_t>(out, static_cast<std::int16_t>(p.valid ? to_units(p.y, 1e-2) : 0));
      append_le<std::int16_t>(out, static_cast<std::int16_t>(p.valid ? to_units(p.z, 1e-2) : 0));
    } else {
      append_le<std::int32_t>(out, p.valid ? to_units(p.x, 1e-3) : 0);
      append_le<std::int32_t>(out, p.valid ? to_units(p.y, 1e-3) : 0);
      append_le<std::int32_t>(out, p.valid ? to_units(p.z, 1e-3) : 0);
    }
    out.push_back(std::byte{p.reflectivity});
    out.push_back(std::byte{p.tag});
  }
  finish_sdk2(h, out);
  return out;
}

std::vector<std::byte> encode_sdk2_imu(const Sdk2Header& header, const Eigen::Vector3d& gyro,
                                       const Eigen::Vector3d& accel) {
  Sdk2Header h = header;
  h.data_type = 0;
  auto out = sdk2_header(h, 1, 24);
  append_imu(out, gyro, accel);
  finish_sdk2(h, out);
  return out;
}

}  // namespace livod::livox
