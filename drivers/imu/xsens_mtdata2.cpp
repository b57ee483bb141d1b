#include "drivers/imu/xsens_mtdata2.hpp"

#include <bit>
#include <cmath>
#include <cstring>

namespace livod::imu {
namespace {

constexpr std::uint8_t kPreamble = 0xFA;
constexpr std::uint8_t kBusMaster = 0xFF;
constexpr std::uint8_t kMidMtData2 = 0x36;
constexpr std::uint8_t kExtendedLength = 0xFF;

constexpr std::uint16_t kXdiTypeMask = 0xFFF0;
constexpr std::uint16_t kXdiPrecisionMask = 0x0003;
constexpr std::uint16_t kXdiPacketCounter = 0x1020;
constexpr std::uint16_t kXdiSampleTimeFine = 0x1060;
constexpr std::uint16_t kXdiAcceleration = 0x4020;
constexpr std::uint16_t kXdiAccelerationHr = 0x4040;
constexpr std::uint16_t kXdiRateOfTurn = 0x8020;
constexpr std::uint16_t kXdiRateOfTurnHr = 0x8040;
constexpr std::uint16_t kXdiStatusWord = 0xE020;

constexpr std::uint32_t kClipBits = 0x3F00;  // StatusWord bits 8-13
constexpr std::int64_t kTickNs = 100'000;    // 10 kHz
constexpr std::int64_t kTickSpan = std::int64_t{1} << 32;
constexpr int kCounterSpan = 1 << 16;

std::uint32_t be32(const std::uint8_t* p) {
  return (static_cast<std::uint32_t>(p[0]) << 24) | (static_cast<std::uint32_t>(p[1]) << 16) |
         (static_cast<std::uint32_t>(p[2]) << 8) | p[3];
}
std::uint16_t be16(const std::uint8_t* p) {
  return static_cast<std::uint16_t>((p[0] << 8) | p[1]);
}

std::size_t real_size(std::uint16_t xdi) {
  switch (xdi & kXdiPrecisionMask) {
    case 0:
    case 1:
      return 4;
    case 2:
      return 6;
    default:
      return 8;
  }
}

double read_real(const std::uint8_t* p, std::uint16_t xdi) {
  switch (xdi & kXdiPrecisionMask) {
    case 0:
      return static_cast<double>(std::bit_cast<float>(be32(p)));
    case 1:
      return static_cast<double>(static_cast<std::int32_t>(be32(p))) / 1048576.0;  // 2^20
    case 2: {
      const auto frac = be32(p);
      const auto integer = static_cast<std::int16_t>(be16(p + 4));
      return static_cast<double>(integer) + static_cast<double>(frac) / 4294967296.0;  // 2^32
    }
    default: {
      const std::uint64_t bits = (static_cast<std::uint64_t>(be32(p)) << 32) | be32(p + 4);
      return std::bit_cast<double>(bits);
    }
  }
}

// Reads a 3-vector item; false when the size does not match its precision.
bool read_vec3(std::span<const std::uint8_t> value, std::uint16_t xdi, Eigen::Vector3d& out) {
  const std::size_t n = real_size(xdi);
  if (value.size() != 3 * n) return false;
  for (int i = 0; i < 3; ++i)
    out[i] = read_real(value.data() + static_cast<std::size_t>(i) * n, xdi);
  return out.allFinite();
}

void put_be(std::vector<std::uint8_t>& out, std::uint64_t v, int bytes) {
  for (int i = bytes - 1; i >= 0; --i)
    out.push_back(static_cast<std::uint8_t>((v >> (8 * i)) & 0xFF));
}

void put_real(std::vector<std::uint8_t>& out, double v, XsensPrecision p) {
  switch (p) {
    case XsensPrecision::float32:
      put_be(out, std::bit_cast<std::uint32_t>(static_cast<float>(v)), 4);
      break;
    case XsensPrecision::fp1220:
      put_be(out,
             static_cast<std::uint32_t>(static_cast<std::int32_t>(std::llround(v * 1048576.0))), 4);
      break;
    case XsensPrecision::fp1632: {
      const auto fixed = static_cast<std::int64_t>(std::llround(v * 4294967296.0));
      put_be(out, static_cast<std::uint32_t>(fixed & 0xFFFFFFFF), 4);
      put_be(out, static_cast<std::uint16_t>(static_cast<std::int16_t>(fixed >> 32)), 2);
      break;
    }
    case XsensPrecision::float64:
      put_be(out, std::bit_cast<std::uint64_t>(v), 8);
      break;
  }
}

}  // namespace

std::optional<std::uint16_t> XsensMtData2Decoder::last_packet_counter() const {
  if (!have_counter_) return std::nullopt;
  return last_counter_;
}

void XsensMtData2Decoder::on_bytes(std::span<const std::byte> bytes, std::int64_t rx_time_ns,
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

void XsensMtData2Decoder::drain(std::int64_t rx_time_ns, const ImuSink& sink) {
  std::size_t pos = 0;
  while (pos < size_) {
    if (buf_[pos] != kPreamble) {
      ++pos;
      ++counters_.skipped_bytes;
      continue;
    }
    const std::size_t avail = size_ - pos;
    if (avail < 4) break;
    std::size_t header = 4;
    std::size_t len = buf_[pos + 3];
    if (len == kExtendedLength) {
      if (avail < 6) break;
      len = be16(&buf_[pos + 4]);
      header = 6;
      if (len > kMaxDataBytes) {  // impossible length: not a preamble after all
        ++counters_.malformed;
        ++pos;
        ++counters_.skipped_bytes;
        continue;
      }
    }
    const std::size_t total = header + len + 1;
    if (avail < total) break;
    std::uint8_t sum = 0;
    for (std::size_t k = 1; k < total; ++k) sum = static_cast<std::uint8_t>(sum + buf_[pos + k]);
    if (sum != 0) {
      // Corrupted, or a 0xFA inside another message's data: resynchronise from the next byte.
      ++counters_.checksum_errors;
      ++pos;
      ++counters_.skipped_bytes;
      continue;
    }
    const std::uint8_t mid = buf_[pos + 2];
    if (mid == kMidMtData2) {
      ++counters_.frames;
      handle_mtdata2({&buf_[pos + header], len}, rx_time_ns, sink);
    } else {
      ++other_messages_;
    }
    pos += total;
  }
  if (pos > 0) {
    std::memmove(buf_.data(), buf_.data() + pos, size_ - pos);
    size_ -= pos;
  }
  if (size_ == buf_.size()) {
    // Cannot happen with a well-formed stream (the buffer holds the largest message); drop a byte
    // so that parsing moves on.
    std::memmove(buf_.data(), buf_.data() + 1, size_ - 1);
    --size_;
    ++counters_.skipped_bytes;
  }
}

void XsensMtData2Decoder::handle_mtdata2(std::span<const std::uint8_t> data,
                                         std::int64_t rx_time_ns, const ImuSink& sink) {
  std::optional<std::uint16_t> counter;
  std::optional<std::uint32_t> ticks;
  std::optional<std::uint32_t> status;
  Eigen::Vector3d accel = Eigen::Vector3d::Zero();
  Eigen::Vector3d gyro = Eigen::Vector3d::Zero();
  bool have_accel = false;
  bool have_gyro = false;
  bool accel_hr = false;
  bool gyro_hr = false;
  std::size_t p = 0;
  while (p < data.size()) {
    if (data.size() - p < 3) {
      ++counters_.malformed;
      return;
    }
    const std::uint16_t xdi = be16(&data[p]);
    const std::size_t size = data[p + 2];
    if (data.size() - p - 3 < size) {
      ++counters_.malformed;
      return;
    }
    const auto value = data.subspan(p + 3, size);
    p += 3 + size;
    const auto type = static_cast<std::uint16_t>(xdi & kXdiTypeMask);
    bool ok = true;
    if (xdi == kXdiPacketCounter) {
      ok = size == 2;
      if (ok) counter = be16(value.data());
    } else if (xdi == kXdiSampleTimeFine) {
      ok = size == 4;
      if (ok) ticks = be32(value.data());
    } else if (xdi == kXdiStatusWord) {
      ok = size == 4;
      if (ok) status = be32(value.data());
    } else if (type == kXdiAcceleration || (type == kXdiAccelerationHr && !have_accel)) {
      Eigen::Vector3d v = Eigen::Vector3d::Zero();
      ok = read_vec3(value, xdi, v);
      // The calibrated output wins over the high-rate one when both come in one message.
      if (ok && (!have_accel || accel_hr)) {
        accel = v;
        accel_hr = type == kXdiAccelerationHr;
        have_accel = true;
      }
    } else if (type == kXdiRateOfTurn || (type == kXdiRateOfTurnHr && !have_gyro)) {
      Eigen::Vector3d v = Eigen::Vector3d::Zero();
      ok = read_vec3(value, xdi, v);
      if (ok && (!have_gyro || gyro_hr)) {
        gyro = v;
        gyro_hr = type == kXdiRateOfTurnHr;
        have_gyro = true;
      }
    }
    if (!ok) {
      ++counters_.malformed;
      return;
    }
  }

  if (counter) {
    if (have_counter_) {
      const int step = (*counter - last_counter_ + kCounterSpan) % kCounterSpan;
      // A backwards step (more than half the counter range) is a device restart, not a gap.
      if (step > 1 && step < kCounterSpan / 2)
        counters_.sequence_gaps += static_cast<std::uint64_t>(step - 1);
    }
    have_counter_ = true;
    last_counter_ = *counter;
  }
  if (status) status_word_ = *status;
  if (!have_accel && !have_gyro) return;  // not IMU data (e.g. orientation only)
  if (!have_accel || !have_gyro || !ticks) {
    ++counters_.incomplete;
    return;
  }
  if (have_time_ && *ticks < last_ticks_ && last_ticks_ - *ticks > 0x80000000U) {
    wrap_ticks_ += kTickSpan;
    ++counters_.counter_wraps;
  }
  have_time_ = true;
  last_ticks_ = *ticks;
  if (status && (*status & kClipBits) != 0) ++counters_.saturated;
  ImuSample sample;
  sample.stamp.sensor = SensorTime((wrap_ticks_ + *ticks) * kTickNs);
  sample.stamp.host = HostTime(rx_time_ns);
  sample.accel_m_s2 = accel;
  sample.gyro_rad_s = gyro;
  ++counters_.samples;
  if (sink) sink(sample);
}

std::vector<std::uint8_t> encode_xbus_message(std::uint8_t mid,
                                              std::span<const std::uint8_t> data) {
  std::vector<std::uint8_t> out;
  out.reserve(data.size() + 7);
  out.push_back(kPreamble);
  out.push_back(kBusMaster);
  out.push_back(mid);
  if (data.size() < kExtendedLength) {
    out.push_back(static_cast<std::uint8_t>(data.size()));
  } else {
    out.push_back(kExtendedLength);
    put_be(out, data.size(), 2);
  }
  out.insert(out.end(), data.begin(), data.end());
  std::uint8_t sum = 0;
  for (std::size_t k = 1; k < out.size(); ++k) sum = static_cast<std::uint8_t>(sum + out[k]);
  out.push_back(static_cast<std::uint8_t>(0x100 - sum));
  return out;
}

std::vector<std::uint8_t> encode_mtdata2_sample(const XsensSample& s) {
  std::vector<std::uint8_t> data;
  const auto prec = static_cast<std::uint16_t>(s.precision);
  auto item = [&data](std::uint16_t xdi, std::size_t size) {
    put_be(data, xdi, 2);
    data.push_back(static_cast<std::uint8_t>(size));
  };
  item(kXdiPacketCounter, 2);
  put_be(data, s.packet_counter, 2);
  item(kXdiSampleTimeFine, 4);
  put_be(data, s.sample_time_fine, 4);
  const std::size_t vec_size = 3 * real_size(prec);
  item(static_cast<std::uint16_t>(kXdiAcceleration | prec), vec_size);
  for (int i = 0; i < 3; ++i) put_real(data, s.accel_m_s2[i], s.precision);
  item(static_cast<std::uint16_t>(kXdiRateOfTurn | prec), vec_size);
  for (int i = 0; i < 3; ++i) put_real(data, s.gyro_rad_s[i], s.precision);
  item(kXdiStatusWord, 4);
  put_be(data, s.status_word, 4);
  return encode_xbus_message(kMidMtData2, data);
}

}  // namespace livod::imu
