#include "drivers/hesai/packet.hpp"

#include <chrono>

#include "core/time.hpp"

namespace livod::drivers::hesai {
namespace {

constexpr std::uint32_t kMicrosecondsPerSecond = 1'000'000;

// PandarXT-32 offsets.
constexpr std::size_t kXtHeaderSize = 12;
constexpr std::size_t kXtBlockSize = 2 + 32 * 4;
constexpr std::size_t kXtTail = kXtHeaderSize + 8 * kXtBlockSize;  // 1052
constexpr std::size_t kXtHighTemperature = kXtTail + 9;
constexpr std::size_t kXtReturnMode = kXtTail + 10;
constexpr std::size_t kXtMotorSpeed = kXtTail + 11;
constexpr std::size_t kXtDate = kXtTail + 13;
constexpr std::size_t kXtTimestamp = kXtTail + 19;
constexpr std::size_t kXtFactory = kXtTail + 23;
constexpr std::size_t kXtSequence = kXtTail + 24;

// Pandar40P offsets.
constexpr std::size_t k40pBlockSize = 4 + 40 * 3;
constexpr std::size_t k40pTail = 10 * k40pBlockSize;  // 1240
constexpr std::size_t k40pHighTemperature = k40pTail + 5;
constexpr std::size_t k40pMotorSpeed = k40pTail + 8;
constexpr std::size_t k40pTimestamp = k40pTail + 10;
constexpr std::size_t k40pReturnMode = k40pTail + 14;
constexpr std::size_t k40pFactory = k40pTail + 15;
constexpr std::size_t k40pDate = k40pTail + 16;
constexpr std::size_t k40pSequence = k40pTail + 22;

std::uint8_t u8(std::span<const std::byte> b, std::size_t at) {
  return static_cast<std::uint8_t>(b[at]);
}
std::uint16_t u16(std::span<const std::byte> b, std::size_t at) {
  return static_cast<std::uint16_t>(u8(b, at) | (u8(b, at + 1) << 8));
}
std::uint32_t u32(std::span<const std::byte> b, std::size_t at) {
  return static_cast<std::uint32_t>(u16(b, at)) |
         (static_cast<std::uint32_t>(u16(b, at + 2)) << 16);
}
void put8(std::vector<std::byte>& b, std::size_t at, std::uint32_t v) {
  b[at] = static_cast<std::byte>(v & 0xFF);
}
void put16(std::vector<std::byte>& b, std::size_t at, std::uint32_t v) {
  put8(b, at, v);
  put8(b, at + 1, v >> 8);
}
void put32(std::vector<std::byte>& b, std::size_t at, std::uint32_t v) {
  put16(b, at, v);
  put16(b, at + 2, v >> 16);
}

bool valid_return_mode(Model model, std::uint8_t mode) {
  switch (mode) {
    case 0x37:
    case 0x38:
    case 0x39:
      return true;
    case 0x33:
    case 0x3B:
    case 0x3C:
      return model == Model::kPandarXT32;
    default:
      return false;
  }
}

// UTC from the tail's date (6 bytes: year since base, month, day, hour, minute, second) and the
// microseconds within the second. False for an impossible date.
bool utc_ns(std::span<const std::byte> b, std::size_t date_at, int year_base, std::uint32_t us,
            std::int64_t& out) {
  using namespace std::chrono;
  const year_month_day ymd{year{year_base + u8(b, date_at)}, month{u8(b, date_at + 1)},
                           day{u8(b, date_at + 2)}};
  const unsigned hh = u8(b, date_at + 3);
  const unsigned mm = u8(b, date_at + 4);
  const unsigned ss = u8(b, date_at + 5);
  // The manuals give 0..1000000 us inclusive; 60 s is a leap second.
  if (!ymd.ok() || hh > 23 || mm > 59 || ss > 60 || us > kMicrosecondsPerSecond) return false;
  const std::int64_t days = sys_days{ymd}.time_since_epoch().count();
  const std::int64_t seconds = days * 86400 + hh * 3600 + mm * 60 + ss;
  out = seconds * kNsPerSecond + static_cast<std::int64_t>(us) * 1000;
  return true;
}

void put_utc(std::vector<std::byte>& b, std::size_t date_at, int year_base, std::int64_t ns,
             std::uint32_t& us) {
  using namespace std::chrono;
  const sys_time<nanoseconds> t{nanoseconds{ns}};
  const sys_days d = floor<days>(t);
  const year_month_day ymd{d};
  const auto in_day = duration_cast<nanoseconds>(t - d).count();
  const auto second_of_day = in_day / kNsPerSecond;
  put8(b, date_at, static_cast<std::uint32_t>(static_cast<int>(ymd.year()) - year_base));
  put8(b, date_at + 1, static_cast<unsigned>(ymd.month()));
  put8(b, date_at + 2, static_cast<unsigned>(ymd.day()));
  put8(b, date_at + 3, static_cast<std::uint32_t>(second_of_day / 3600));
  put8(b, date_at + 4, static_cast<std::uint32_t>(second_of_day / 60 % 60));
  put8(b, date_at + 5, static_cast<std::uint32_t>(second_of_day % 60));
  us = static_cast<std::uint32_t>(in_day % kNsPerSecond / 1000);
}

PacketError decode_xt(std::span<const std::byte> b, HesaiPacket& out) {
  const ModelTraits& t = traits(Model::kPandarXT32);
  if (b.size() != kXt32PacketSize && b.size() != kXt32PacketSizeNoSequence) {
    return PacketError::kWrongSize;
  }
  if (u8(b, 0) != 0xEE || u8(b, 1) != 0xFF || u8(b, 2) != t.protocol_major ||
      u8(b, 3) != t.protocol_minor) {
    return PacketError::kBadHeader;
  }
  if (u8(b, 6) != t.channels || u8(b, 7) != t.blocks) return PacketError::kWrongModel;
  const bool has_sequence = (u8(b, 11) & 0x01) != 0;
  if (has_sequence != (b.size() == kXt32PacketSize) || u8(b, 9) == 0) {
    return PacketError::kBadHeader;
  }
  out.model = Model::kPandarXT32;
  out.first_block_return = u8(b, 8);
  out.distance_unit_m = u8(b, 9) * 1e-3;
  const std::uint8_t returns = u8(b, 10);
  out.return_mode = u8(b, kXtReturnMode);
  if (!valid_return_mode(Model::kPandarXT32, out.return_mode) || returns < 1 || returns > 2 ||
      (returns == 2) != is_dual_return(out.return_mode)) {
    return PacketError::kBadReturnMode;
  }
  out.returns = returns;
  for (int blk = 0; blk < t.blocks; ++blk) {
    const std::size_t base = kXtHeaderSize + static_cast<std::size_t>(blk) * kXtBlockSize;
    const std::uint16_t azimuth = u16(b, base);
    if (azimuth >= 36000) return PacketError::kBadAzimuth;
    out.azimuth[static_cast<std::size_t>(blk)] = azimuth;
    for (int c = 0; c < t.channels; ++c) {
      const std::size_t at = base + 2 + static_cast<std::size_t>(c) * 4;
      const auto i = static_cast<std::size_t>(blk * kMaxChannels + c);
      out.distance[i] = u16(b, at);
      out.reflectivity[i] = u8(b, at + 2);
    }
  }
  out.high_temperature = u8(b, kXtHighTemperature) != 0;
  out.motor_rpm = u16(b, kXtMotorSpeed);
  out.factory = u8(b, kXtFactory);
  if (!utc_ns(b, kXtDate, t.date_year_base, u32(b, kXtTimestamp), out.timestamp_ns)) {
    return PacketError::kBadTime;
  }
  out.udp_sequence.reset();
  if (has_sequence) out.udp_sequence = u32(b, kXtSequence);
  return PacketError::kNone;
}

PacketError decode_40p(std::span<const std::byte> b, HesaiPacket& out) {
  const ModelTraits& t = traits(Model::kPandar40P);
  if (b.size() != kPandar40pPacketSize && b.size() != kPandar40pPacketSizeWithSequence) {
    return PacketError::kWrongSize;
  }
  for (int blk = 0; blk < t.blocks; ++blk) {
    const std::size_t base = static_cast<std::size_t>(blk) * k40pBlockSize;
    if (u8(b, base) != 0xFF || u8(b, base + 1) != 0xEE) return PacketError::kBadHeader;
  }
  out.model = Model::kPandar40P;
  out.first_block_return = 0;
  out.distance_unit_m = t.distance_unit_m;
  out.return_mode = u8(b, k40pReturnMode);
  if (!valid_return_mode(Model::kPandar40P, out.return_mode)) return PacketError::kBadReturnMode;
  out.returns = is_dual_return(out.return_mode) ? 2 : 1;
  for (int blk = 0; blk < t.blocks; ++blk) {
    const std::size_t base = static_cast<std::size_t>(blk) * k40pBlockSize;
    const std::uint16_t azimuth = u16(b, base + 2);
    if (azimuth >= 36000) return PacketError::kBadAzimuth;
    out.azimuth[static_cast<std::size_t>(blk)] = azimuth;
    for (int c = 0; c < t.channels; ++c) {
      const std::size_t at = base + 4 + static_cast<std::size_t>(c) * 3;
      const auto i = static_cast<std::size_t>(blk * kMaxChannels + c);
      out.distance[i] = u16(b, at);
      out.reflectivity[i] = u8(b, at + 2);
    }
  }
  out.high_temperature = u8(b, k40pHighTemperature) != 0;
  out.motor_rpm = u16(b, k40pMotorSpeed);
  out.factory = u8(b, k40pFactory);
  if (!utc_ns(b, k40pDate, t.date_year_base, u32(b, k40pTimestamp), out.timestamp_ns)) {
    return PacketError::kBadTime;
  }
  out.udp_sequence.reset();
  if (b.size() == kPandar40pPacketSizeWithSequence) out.udp_sequence = u32(b, k40pSequence);
  return PacketError::kNone;
}

}  // namespace

const char* to_string(PacketError e) {
  switch (e) {
    case PacketError::kNone:
      return "ok";
    case PacketError::kWrongSize:
      return "length of no packet of this model";
    case PacketError::kBadHeader:
      return "header or block flags of another protocol";
    case PacketError::kWrongModel:
      return "laser or block count of another model";
    case PacketError::kBadAzimuth:
      return "azimuth of 360 degrees or more";
    case PacketError::kBadReturnMode:
      return "unknown or inconsistent return mode";
    case PacketError::kBadTime:
      return "impossible date or microseconds";
  }
  return "unknown";
}

bool is_dual_return(std::uint8_t return_mode) {
  return return_mode == 0x39 || return_mode == 0x3B || return_mode == 0x3C;
}

PacketError decode_packet(Model model, std::span<const std::byte> payload, HesaiPacket& out) {
  return model == Model::kPandarXT32 ? decode_xt(payload, out) : decode_40p(payload, out);
}

std::vector<std::byte> encode_packet(const HesaiPacket& p) {
  const ModelTraits& t = traits(p.model);
  std::vector<std::byte> b;
  std::uint32_t us = 0;
  if (p.model == Model::kPandarXT32) {
    b.assign(p.udp_sequence ? kXt32PacketSize : kXt32PacketSizeNoSequence, std::byte{0});
    put8(b, 0, 0xEE);
    put8(b, 1, 0xFF);
    put8(b, 2, t.protocol_major);
    put8(b, 3, t.protocol_minor);
    put8(b, 6, static_cast<std::uint32_t>(t.channels));
    put8(b, 7, static_cast<std::uint32_t>(t.blocks));
    put8(b, 8, p.first_block_return);
    put8(b, 9, static_cast<std::uint32_t>(p.distance_unit_m * 1e3 + 0.5));
    put8(b, 10, static_cast<std::uint32_t>(p.returns));
    put8(b, 11, p.udp_sequence ? 1U : 0U);
    for (int blk = 0; blk < t.blocks; ++blk) {
      const std::size_t base = kXtHeaderSize + static_cast<std::size_t>(blk) * kXtBlockSize;
      put16(b, base, p.azimuth[static_cast<std::size_t>(blk)]);
      for (int c = 0; c < t.channels; ++c) {
        const std::size_t at = base + 2 + static_cast<std::size_t>(c) * 4;
        put16(b, at, p.raw_distance(blk, c));
        put8(b, at + 2, p.raw_reflectivity(blk, c));
      }
    }
    put8(b, kXtHighTemperature, p.high_temperature ? 1U : 0U);
    put8(b, kXtReturnMode, p.return_mode);
    put16(b, kXtMotorSpeed, p.motor_rpm);
    put_utc(b, kXtDate, t.date_year_base, p.timestamp_ns, us);
    put32(b, kXtTimestamp, us);
    put8(b, kXtFactory, p.factory);
    if (p.udp_sequence) put32(b, kXtSequence, *p.udp_sequence);
    return b;
  }
  b.assign(p.udp_sequence ? kPandar40pPacketSizeWithSequence : kPandar40pPacketSize, std::byte{0});
  for (int blk = 0; blk < t.blocks; ++blk) {
    const std::size_t base = static_cast<std::size_t>(blk) * k40pBlockSize;
    put8(b, base, 0xFF);
    put8(b, base + 1, 0xEE);
    put16(b, base + 2, p.azimuth[static_cast<std::size_t>(blk)]);
    for (int c = 0; c < t.channels; ++c) {
      const std::size_t at = base + 4 + static_cast<std::size_t>(c) * 3;
      put16(b, at, p.raw_distance(blk, c));
      put8(b, at + 2, p.raw_reflectivity(blk, c));
    }
  }
  put8(b, k40pHighTemperature, p.high_temperature ? 1U : 0U);
  put16(b, k40pMotorSpeed, p.motor_rpm);
  put8(b, k40pReturnMode, p.return_mode);
  put8(b, k40pFactory, p.factory);
  put_utc(b, k40pDate, t.date_year_base, p.timestamp_ns, us);
  put32(b, k40pTimestamp, us);
  if (p.udp_sequence) put32(b, k40pSequence, *p.udp_sequence);
  return b;
}

}  // namespace livod::drivers::hesai
