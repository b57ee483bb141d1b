#include "drivers/scan_writer.hpp"

#include <algorithm>
#include <cctype>
#include <cinttypes>
#include <cstdio>
#include <cstring>

#include "core/error.hpp"
#include "io/pcd_writer.hpp"

namespace livod::drivers {
namespace {

// The header's counts are right-aligned in fixed-width fields so that close() can rewrite
// them in place; PCD readers split header lines on any whitespace.
constexpr int kCountWidth = 20;

// printf-style append (livod_drivers does not link fmt).
template <class... Args>
void append_text(std::string& out, const char* format, Args... args) {
  char line[160];
  const int n = std::snprintf(line, sizeof line, format, args...);
  if (n > 0) out.append(line, std::min(static_cast<std::size_t>(n), sizeof line - 1));
}

template <class T>
void append_raw(std::string& out, const T& value) {
  char bytes[sizeof(T)];
  std::memcpy(bytes, &value, sizeof(T));
  out.append(bytes, sizeof(T));
}

}  // namespace

std::optional<ScanFileFormat> scan_format_for(const std::filesystem::path& path, bool pcd_ascii) {
  std::string ext = path.extension().string();
  std::transform(ext.begin(), ext.end(), ext.begin(),
                 [](unsigned char c) { return static_cast<char>(std::tolower(c)); });
  if (ext == ".csv") return ScanFileFormat::kCsv;
  if (ext == ".pcd") return pcd_ascii ? ScanFileFormat::kPcdAscii : ScanFileFormat::kPcdBinary;
  return std::nullopt;
}

ScanWriter::ScanWriter(const std::filesystem::path& path, ScanFileFormat format)
    : path_(path), format_(format), out_(path, std::ios::binary | std::ios::trunc) {
  if (!out_) throw Error("cannot create " + path.string());
  if (format_ == ScanFileFormat::kCsv) {
    out_ << "frame,x,y,z,intensity,t_ns,ring,return\n";
  } else {
    write_pcd_header(0);
  }
}

ScanWriter::~ScanWriter() {
  try {
    close();
  } catch (const std::exception&) {  // NOLINT(bugprone-empty-catch): destructors must not throw
  }
}

void ScanWriter::write_pcd_header(std::uint64_t points) {
  const std::string header =
      io::pcd_header({{"x"}, {"y"}, {"z"}, {"intensity"}, {"t", 8}, {"ring", 2, 'U'}}, points,
                     format_ != ScanFileFormat::kPcdAscii, "livod decode", kCountWidth);
  out_.write(header.data(), static_cast<std::streamsize>(header.size()));
}

void ScanWriter::write(const LidarScan& scan) {
  if (closed_) throw Error(path_.string() + ": write after close");
  buffer_.clear();
  const std::uint64_t frame = scans_;
  std::uint64_t written = 0;
  for (std::size_t i = 0; i < scan.size(); ++i) {
    if (scan.valid[i] == 0) continue;
    const std::int64_t t_ns = scan.start.sensor.ns + scan.t_offset_ns[i];
    switch (format_) {
      case ScanFileFormat::kCsv:
        append_text(buffer_, "%" PRIu64 ",%.6f,%.6f,%.6f,%g,%" PRId64 ",%u,%u\n", frame,
                    static_cast<double>(scan.x[i]), static_cast<double>(scan.y[i]),
                    static_cast<double>(scan.z[i]), static_cast<double>(scan.intensity[i]), t_ns,
                    static_cast<unsigned>(scan.ring[i]),
                    static_cast<unsigned>(scan.return_index[i]));
        break;
      case ScanFileFormat::kPcdAscii:
        append_text(buffer_, "%.6f %.6f %.6f %g %.9f %u\n", static_cast<double>(scan.x[i]),
                    static_cast<double>(scan.y[i]), static_cast<double>(scan.z[i]),
                    static_cast<double>(scan.intensity[i]), static_cast<double>(t_ns) * 1e-9,
                    static_cast<unsigned>(scan.ring[i]));
        break;
      case ScanFileFormat::kPcdBinary:
        append_raw(buffer_, scan.x[i]);
        append_raw(buffer_, scan.y[i]);
        append_raw(buffer_, scan.z[i]);
        append_raw(buffer_, scan.intensity[i]);
        append_raw(buffer_, static_cast<double>(t_ns) * 1e-9);
        append_raw(buffer_, scan.ring[i]);
        break;
    }
    ++written;
  }
  out_.write(buffer_.data(), static_cast<std::streamsize>(buffer_.size()));
  if (!out_) throw Error("write failed: " + path_.string());
  ++scans_;
  points_ += written;
}

void ScanWriter::close() {
  if (closed_) return;
  closed_ = true;
  if (format_ != ScanFileFormat::kCsv) {
    out_.seekp(0);
    write_pcd_header(points_);
  }
  out_.close();
  if (!out_) throw Error("write failed: " + path_.string());
}

}  // namespace livod::drivers
