#pragma once
// Test support: just enough of the ZIP format (APPNOTE 6.3) to read evo's result files, and of
// NumPy's .npy format to read the arrays inside them. Header-only, tests only.
//
// ZIP: end-of-central-directory record -> central directory -> local file headers. Entries are
// stored (method 0) or deflated (method 8, raw deflate through zlib); CRC-32 is checked. No
// ZIP64, no encryption, no multi-disk archives. Every offset and length is checked against the
// buffer; problems raise livod::FormatError with the byte offset.
//
// NPY: magic "\x93NUMPY", version 1.x/2.x/3.x header dict; only 1-D little-endian float64
// ('<f8', C order) arrays, which is what evo stores.

#include <zlib.h>

#include <cstdint>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>
#include <string_view>
#include <vector>

#include "core/error.hpp"

namespace livod::eval::test_support {

class ZipArchive {
 public:
  struct Entry {
    std::string name;
    std::uint16_t method = 0;
    std::uint32_t crc32 = 0;
    std::uint64_t compressed_size = 0;
    std::uint64_t uncompressed_size = 0;
    std::uint64_t local_header_offset = 0;
  };

  static ZipArchive open(const std::filesystem::path& path) {
    std::ifstream in(path, std::ios::binary);
    if (!in) throw Error("cannot open '" + path.string() + "'");
    std::ostringstream buffer;
    buffer << in.rdbuf();
    return ZipArchive(std::move(buffer).str(), path.string());
  }

  ZipArchive(std::string bytes, std::string source)
      : bytes_(std::move(bytes)), source_(std::move(source)) {
    read_central_directory();
  }

  [[nodiscard]] const std::vector<Entry>& entries() const { return entries_; }

  [[nodiscard]] bool contains(const std::string& name) const { return find(name) != nullptr; }

  // The uncompressed contents of entry `name`.
  [[nodiscard]] std::string read(const std::string& name) const {
    const Entry* e = find(name);
    if (e == nullptr) throw Error(source_ + ": no entry '" + name + "'");
    const std::uint64_t h = e->local_header_offset;
    if (u32(h) != kLocalHeaderSignature) fail(h, "bad local file header signature");
    const std::uint64_t data = h + 30 + u16(h + 26) + u16(h + 28);
    check_range(data, e->compressed_size, "entry data");
    const std::string_view raw(bytes_.data() + data, e->compressed_size);
    std::string out;
    if (e->method == 0) {
      if (e->compressed_size != e->uncompressed_size) fail(h, "stored entry with size mismatch");
      out.assign(raw);
    } else if (e->method == 8) {
      out = inflate_raw(raw, e->uncompressed_size, data);
    } else {
      fail(h, "unsupported compression method " + std::to_string(e->method));
    }
    const auto crc = static_cast<std::uint32_t>(
        ::crc32(0L, reinterpret_cast<const Bytef*>(out.data()), static_cast<uInt>(out.size())));
    if (crc != e->crc32) fail(h, "CRC-32 mismatch in '" + e->name + "'");
    return out;
  }

 private:
  static constexpr std::uint32_t kEndSignature = 0x06054b50;
  static constexpr std::uint32_t kCentralSignature = 0x02014b50;
  static constexpr std::uint32_t kLocalHeaderSignature = 0x04034b50;
  static constexpr std::uint64_t kEndRecordSize = 22;
  static constexpr std::uint64_t kMaxCommentSize = 0xffff;

  [[noreturn]] void fail(std::uint64_t offset, const std::string& message) const {
    throw FormatError(source_, offset, message);
  }

  void check_range(std::uint64_t offset, std::uint64_t length, const char* what) const {
    if (offset > bytes_.size() || length > bytes_.size() - offset) {
      fail(offset, std::string(what) + " runs past the end of the file");
    }
  }

  [[nodiscard]] std::uint16_t u16(std::uint64_t offset) const {
    check_range(offset, 2, "field");
    const auto* p = reinterpret_cast<const unsigned char*>(bytes_.data() + offset);
    return static_cast<std::uint16_t>(p[0] | (p[1] << 8));
  }

  [[nodiscard]] std::uint32_t u32(std::uint64_t offset) const {
    check_range(offset, 4, "field");
    const auto* p = reinterpret_cast<const unsigned char*>(bytes_.data() + offset);
    return static_cast<std::uint32_t>(p[0]) | (static_cast<std::uint32_t>(p[1]) << 8) |
           (static_cast<std::uint32_t>(p[2]) << 16) | (static_cast<std::uint32_t>(p[3]) << 24);
  }

  void read_central_directory() {
    if (bytes_.size() < kEndRecordSize) fail(0, "too short for a ZIP file");
    // The end record sits before an optional comment of up to 65535 bytes: scan backwards.
    std::uint64_t end = bytes_.size() - kEndRecordSize;
    const std::uint64_t lowest = end > kMaxCommentSize ? end - kMaxCommentSize : 0;
    while (u32(end) != kEndSignature) {
      if (end == lowest) fail(0, "no end-of-central-directory record");
      --end;
    }
    const std::uint16_t count = u16(end + 10);
    const std::uint32_t cd_size = u32(end + 12);
    std::uint64_t pos = u32(end + 16);
    check_range(pos, cd_size, "central directory");
    for (std::uint16_t i = 0; i < count; ++i) {
      if (u32(pos) != kCentralSignature) fail(pos, "bad central directory signature");
      Entry e;
      e.method = u16(pos + 10);
      e.crc32 = u32(pos + 16);
      e.compressed_size = u32(pos + 20);
      e.uncompressed_size = u32(pos + 24);
      const std::uint16_t name_len = u16(pos + 28);
      const std::uint16_t extra_len = u16(pos + 30);
      const std::uint16_t comment_len = u16(pos + 32);
      e.local_header_offset = u32(pos + 42);
      check_range(pos + 46, name_len, "file name");
      e.name.assign(bytes_.data() + pos + 46, name_len);
      entries_.push_back(std::move(e));
      pos += 46 + static_cast<std::uint64_t>(name_len) + extra_len + comment_len;
    }
  }

  [[nodiscard]] std::string inflate_raw(std::string_view raw, std::uint64_t expected,
                                        std::uint64_t offset) const {
    std::string out(expected, '\0');
    z_stream z{};
    // Negative window bits: raw deflate data, no zlib header (as ZIP stores it).
    if (inflateInit2(&z, -MAX_WBITS) != Z_OK) fail(offset, "inflateInit2 failed");
    z.next_in = reinterpret_cast<Bytef*>(const_cast<char*>(raw.data()));
    z.avail_in = static_cast<uInt>(raw.size());
    z.next_out = reinterpret_cast<Bytef*>(out.data());
    z.avail_out = static_cast<uInt>(out.size());
    const int rc = ::inflate(&z, Z_FINISH);
    const std::uint64_t produced = z.total_out;
    inflateEnd(&z);
    if (rc != Z_STREAM_END || produced != expected) fail(offset, "corrupt deflate stream");
    return out;
  }

  [[nodiscard]] const Entry* find(const std::string& name) const {
    for (const Entry& e : entries_) {
      if (e.name == name) return &e;
    }
    return nullptr;
  }

  std::string bytes_;
  std::string source_;
  std::vector<Entry> entries_;
};

// A 1-D '<f8' array from .npy bytes.
inline std::vector<double> parse_npy_f8(std::string_view bytes, const std::string& source) {
  constexpr std::string_view kMagic("\x93NUMPY", 6);
  if (bytes.size() < 10 || bytes.substr(0, 6) != kMagic) {
    throw FormatError(source, 0, "not a .npy array");
  }
  const auto major = static_cast<unsigned char>(bytes[6]);
  std::size_t header_len = 0;
  std::size_t header_start = 0;
  const auto byte = [&](std::size_t i) {
    return static_cast<std::size_t>(static_cast<unsigned char>(bytes[i]));
  };
  if (major == 1) {
    header_len = byte(8) | (byte(9) << 8);
    header_start = 10;
  } else if (major == 2 || major == 3) {
    if (bytes.size() < 12) throw FormatError(source, 8, "truncated .npy header");
    header_len = byte(8) | (byte(9) << 8) | (byte(10) << 16) | (byte(11) << 24);
    header_start = 12;
  } else {
    throw FormatError(source, 6, "unsupported .npy version " + std::to_string(major));
  }
  if (header_len > bytes.size() - header_start) {
    throw FormatError(source, header_start, "truncated .npy header");
  }
  const std::string_view header = bytes.substr(header_start, header_len);
  if (header.find("'descr': '<f8'") == std::string_view::npos) {
    throw FormatError(source, header_start, "only '<f8' arrays are supported");
  }
  if (header.find("'fortran_order': False") == std::string_view::npos) {
    throw FormatError(source, header_start, "only C-order arrays are supported");
  }
  const std::size_t shape = header.find("'shape': (");
  if (shape == std::string_view::npos) throw FormatError(source, header_start, "no shape");
  std::size_t count = 0;
  std::size_t i = shape + 10;
  bool digits = false;
  while (i < header.size() && header[i] >= '0' && header[i] <= '9') {
    count = count * 10 + static_cast<std::size_t>(header[i] - '0');
    digits = true;
    ++i;
  }
  // "(N,)" is 1-D; anything else (a second dimension, an empty shape) is rejected.
  if (!digits || i + 1 >= header.size() || header[i] != ',' || header[i + 1] != ')') {
    throw FormatError(source, header_start + i, "only 1-D arrays are supported");
  }
  const std::size_t data = header_start + header_len;
  if (count > (bytes.size() - data) / 8 || bytes.size() - data != count * 8) {
    throw FormatError(source, data, "array data size does not match its shape");
  }
  std::vector<double> out(count);
  for (std::size_t k = 0; k < count; ++k) {
    std::uint64_t bits = 0;
    for (std::size_t b = 0; b < 8; ++b)
      bits |= static_cast<std::uint64_t>(byte(data + 8 * k + b)) << (8 * b);
    static_assert(sizeof(double) == sizeof(std::uint64_t));
    double v = 0.0;
    std::memcpy(&v, &bits, sizeof v);
    out[k] = v;
  }
  return out;
}

}  // namespace livod::eval::test_support
