#include "io/serial_capture.hpp"

#include <array>
#include <cstring>
#include <sstream>
#include <stdexcept>

#include "core/error.hpp"

namespace livod::io {
namespace {

constexpr std::array<char, 8> kMagic{'L', 'V', 'S', 'E', 'R', 'C', 'A', 'P'};
constexpr std::uint32_t kVersion = 1;
constexpr std::size_t kHeaderBytes = 16;
constexpr std::size_t kRecordHeaderBytes = 12;
static_assert(serial_record_bytes(0) == kRecordHeaderBytes);

std::uint64_t le(const unsigned char* p, int n) {
  std::uint64_t v = 0;
  for (int i = n - 1; i >= 0; --i) v = (v << 8) | p[i];
  return v;
}

void put_le(std::ostream& out, std::uint64_t v, int n) {
  for (int i = 0; i < n; ++i) out.put(static_cast<char>((v >> (8 * i)) & 0xFF));
}

void put_le(std::vector<std::byte>& out, std::uint64_t v, int n) {
  for (int i = 0; i < n; ++i) out.push_back(static_cast<std::byte>((v >> (8 * i)) & 0xFF));
}

}  // namespace

std::vector<std::byte> serial_capture_header() {
  std::vector<std::byte> out;
  out.reserve(kHeaderBytes);
  for (const char c : kMagic) out.push_back(static_cast<std::byte>(c));
  put_le(out, kVersion, 4);
  put_le(out, 0, 4);
  return out;
}

void append_serial_record(std::vector<std::byte>& out, std::int64_t rx_time_ns,
                          std::span<const std::byte> bytes) {
  if (bytes.empty() || bytes.size() > SerialCaptureReader::kMaxChunkBytes) {
    throw std::invalid_argument("serial capture chunk of " + std::to_string(bytes.size()) +
                                " bytes: the format takes 1 to " +
                                std::to_string(SerialCaptureReader::kMaxChunkBytes));
  }
  put_le(out, static_cast<std::uint64_t>(rx_time_ns), 8);
  put_le(out, bytes.size(), 4);
  out.insert(out.end(), bytes.begin(), bytes.end());
}

struct SerialCaptureReader::Impl {
  std::string name;
  std::unique_ptr<std::istream> in;
  std::uint64_t offset = 0;
  std::uint64_t chunks = 0;
  std::uint64_t bytes = 0;

  // Reads exactly n bytes; false at a clean end (nothing read), FormatError when cut short.
  bool read_exact(void* dst, std::size_t n, bool end_ok) {
    in->read(static_cast<char*>(dst), static_cast<std::streamsize>(n));
    const auto got = static_cast<std::size_t>(in->gcount());
    if (got == n) {
      offset += n;
      return true;
    }
    if (got == 0 && end_ok) return false;
    throw FormatError(
        name, offset + got,
        "truncated record (" + std::to_string(got) + " of " + std::to_string(n) + " bytes)");
  }

  void read_header() {
    std::array<unsigned char, kHeaderBytes> h{};
    if (!read_exact(h.data(), h.size(), true) || std::memcmp(h.data(), kMagic.data(), 8) != 0) {
      throw FormatError(name, 0, "not a livod serial capture (no LVSERCAP header)");
    }
    const auto version = static_cast<std::uint32_t>(le(h.data() + 8, 4));
    if (version != kVersion) {
      throw FormatError(name, 8, "unsupported serial capture version " + std::to_string(version));
    }
  }
};

SerialCaptureReader::SerialCaptureReader(std::unique_ptr<Impl> impl) : impl_(std::move(impl)) {
  impl_->read_header();
}

SerialCaptureReader::SerialCaptureReader(const std::filesystem::path& path)
    : SerialCaptureReader([&] {
        auto impl = std::make_unique<Impl>();
        impl->name = path.string();
        auto file = std::make_unique<std::ifstream>(path, std::ios::binary);
        if (!*file) throw Error("cannot open serial capture " + path.string());
        impl->in = std::move(file);
        return impl;
      }()) {}

SerialCaptureReader SerialCaptureReader::from_memory(std::string_view data, std::string name) {
  auto impl = std::make_unique<Impl>();
  impl->name = std::move(name);
  impl->in = std::make_unique<std::istringstream>(std::string(data));
  return SerialCaptureReader(std::move(impl));
}

SerialCaptureReader::~SerialCaptureReader() = default;
SerialCaptureReader::SerialCaptureReader(SerialCaptureReader&&) noexcept = default;
SerialCaptureReader& SerialCaptureReader::operator=(SerialCaptureReader&&) noexcept = default;

bool SerialCaptureReader::next(SerialChunk& chunk) {
  std::array<unsigned char, kRecordHeaderBytes> h{};
  const std::uint64_t record_offset = impl_->offset;
  if (!impl_->read_exact(h.data(), h.size(), true)) return false;
  const auto length = static_cast<std::uint32_t>(le(h.data() + 8, 4));
  if (length == 0 || length > kMaxChunkBytes) {
    throw FormatError(impl_->name, record_offset + 8,
                      "impossible chunk length " + std::to_string(length));
  }
  chunk.rx_time_ns = static_cast<std::int64_t>(le(h.data(), 8));
  chunk.bytes.resize(length);
  impl_->read_exact(chunk.bytes.data(), length, false);
  ++impl_->chunks;
  impl_->bytes += length;
  return true;
}

std::uint64_t SerialCaptureReader::chunks() const {
  return impl_->chunks;
}

std::uint64_t SerialCaptureReader::bytes() const {
  return impl_->bytes;
}

SerialCaptureWriter::SerialCaptureWriter(const std::filesystem::path& path)
    : path_(path.string()), out_(path, std::ios::binary | std::ios::trunc) {
  if (!out_) throw Error("cannot create serial capture " + path_);
  out_.write(kMagic.data(), kMagic.size());
  put_le(out_, kVersion, 4);
  put_le(out_, 0, 4);
}

void SerialCaptureWriter::write(std::int64_t rx_time_ns, std::span<const std::byte> bytes) {
  if (bytes.empty()) return;
  if (bytes.size() > SerialCaptureReader::kMaxChunkBytes) {
    throw std::invalid_argument("serial capture chunk of " + std::to_string(bytes.size()) +
                                " bytes exceeds the format's limit");
  }
  put_le(out_, static_cast<std::uint64_t>(rx_time_ns), 8);
  put_le(out_, bytes.size(), 4);
  out_.write(reinterpret_cast<const char*>(bytes.data()),
             static_cast<std::streamsize>(bytes.size()));
}

void SerialCaptureWriter::flush() {
  out_.flush();
  if (!out_) throw Error("cannot write serial capture " + path_);
}

}  // namespace livod::io
