#include "io/lcm_log.hpp"

#include <fcntl.h>
#include <sys/stat.h>
#include <unistd.h>

#include <algorithm>
#include <array>
#include <cerrno>
#include <cstdio>
#include <cstring>
#include <limits>
#include <utility>
#include <vector>

#include "core/error.hpp"

namespace livod::io {
namespace {

constexpr std::array<std::byte, 4> kSyncBytes{std::byte{0xED}, std::byte{0xA1}, std::byte{0xDA},
                                              std::byte{0x01}};
// Resynchronisation reads the file in chunks of this size while looking for the sync word.
constexpr std::size_t kScanChunkSize = 64 * 1024;

std::uint32_t load_be32(const std::byte* p) {
  return (std::to_integer<std::uint32_t>(p[0]) << 24) |
         (std::to_integer<std::uint32_t>(p[1]) << 16) |
         (std::to_integer<std::uint32_t>(p[2]) << 8) | std::to_integer<std::uint32_t>(p[3]);
}

std::uint64_t load_be64(const std::byte* p) {
  return (std::uint64_t{load_be32(p)} << 32) | load_be32(p + 4);
}

void store_be32(std::byte* p, std::uint32_t v) {
  p[0] = static_cast<std::byte>(v >> 24);
  p[1] = static_cast<std::byte>(v >> 16);
  p[2] = static_cast<std::byte>(v >> 8);
  p[3] = static_cast<std::byte>(v);
}

void store_be64(std::byte* p, std::uint64_t v) {
  store_be32(p, static_cast<std::uint32_t>(v >> 32));
  store_be32(p + 4, static_cast<std::uint32_t>(v));
}

std::string errno_text() {
  return std::strerror(errno);
}

// Random-access bytes: a file (pread) or a caller-owned memory block.
class ByteSource {
 public:
  virtual ~ByteSource() = default;
  [[nodiscard]] virtual std::uint64_t size() const = 0;
  // Copies exactly out.size() bytes from `offset`; the caller has checked the range.
  virtual void read(std::uint64_t offset, std::span<std::byte> out) = 0;
};

class FileSource final : public ByteSource {
 public:
  explicit FileSource(const std::filesystem::path& path) : path_(path.string()) {
    fd_ = ::open(path_.c_str(), O_RDONLY | O_CLOEXEC);
    if (fd_ < 0) throw Error(path_ + ": cannot open LCM log: " + errno_text());
    struct stat st {};
    if (::fstat(fd_, &st) != 0) {
      const std::string msg = errno_text();
      ::close(fd_);
      throw Error(path_ + ": cannot stat LCM log: " + msg);
    }
    if (!S_ISREG(st.st_mode)) {
      ::close(fd_);
      throw Error(path_ + ": not a regular file");
    }
    size_ = static_cast<std::uint64_t>(st.st_size);
  }
  ~FileSource() override { ::close(fd_); }
  FileSource(const FileSource&) = delete;
  FileSource& operator=(const FileSource&) = delete;

  [[nodiscard]] std::uint64_t size() const override { return size_; }

  void read(std::uint64_t offset, std::span<std::byte> out) override {
    std::size_t done = 0;
    while (done < out.size()) {
      const ssize_t n =
          ::pread(fd_, out.data() + done, out.size() - done, static_cast<off_t>(offset + done));
      if (n < 0 && errno == EINTR) continue;
      if (n < 0) throw Error(path_ + ": read error: " + errno_text());
      // The file shrank under us (a logger truncating it): report where the bytes ran out.
      if (n == 0) throw FormatError(path_, offset + done, "file ended unexpectedly while reading");
      done += static_cast<std::size_t>(n);
    }
  }

 private:
  std::string path_;
  int fd_ = -1;
  std::uint64_t size_ = 0;
};

class MemorySource final : public ByteSource {
 public:
  explicit MemorySource(std::span<const std::byte> bytes) : bytes_(bytes) {}
  [[nodiscard]] std::uint64_t size() const override { return bytes_.size(); }
  void read(std::uint64_t offset, std::span<std::byte> out) override {
    std::copy_n(bytes_.begin() + static_cast<std::ptrdiff_t>(offset), out.size(), out.begin());
  }

 private:
  std::span<const std::byte> bytes_;
};

}  // namespace

struct LcmLogReader::Impl {
  std::unique_ptr<ByteSource> source;
  std::string source_name;
  LcmLogReaderOptions options;
  LcmLogStats stats;
  std::uint64_t position = 0;
  // Channel + data of the current event; grows to the largest event and is then reused.
  std::vector<std::byte> body;
  std::vector<std::byte> scan_buffer;

  struct Header {
    std::int64_t event_number;
    std::int64_t timestamp_us;
    std::size_t channel_length;
    std::size_t data_length;
  };

  // Validates the header at `offset`; returns an explanation when it is not a usable event.
  std::optional<std::string> parse_header(std::uint64_t offset, Header& header) {
    const std::uint64_t remaining = source->size() - offset;
    if (remaining < kLcmLogHeaderSize) {
      return "truncated event header (" + std::to_string(remaining) + " bytes left, need " +
             std::to_string(kLcmLogHeaderSize) + ")";
    }
    std::array<std::byte, kLcmLogHeaderSize> raw{};
    source->read(offset, raw);
    const std::uint32_t sync = load_be32(raw.data());
    if (sync != kLcmLogSyncWord) {
      char text[16];
      std::snprintf(text, sizeof(text), "0x%08X", sync);
      return std::string("bad sync word ") + text + " (expected 0xEDA1DA01)";
    }
    header.event_number = static_cast<std::int64_t>(load_be64(raw.data() + 4));
    header.timestamp_us = static_cast<std::int64_t>(load_be64(raw.data() + 12));
    const auto channel_length = static_cast<std::int32_t>(load_be32(raw.data() + 20));
    const auto data_length = static_cast<std::int32_t>(load_be32(raw.data() + 24));
    if (channel_length <= 0 ||
        static_cast<std::uint64_t>(channel_length) > options.max_channel_length) {
      return "channel length " + std::to_string(channel_length) + " out of range [1, " +
             std::to_string(options.max_channel_length) + "]";
    }
    if (data_length < 0 || static_cast<std::uint64_t>(data_length) > options.max_data_length) {
      return "data length " + std::to_string(data_length) + " out of range [0, " +
             std::to_string(options.max_data_length) + "]";
    }
    header.channel_length = static_cast<std::size_t>(channel_length);
    header.data_length = static_cast<std::size_t>(data_length);
    const std::uint64_t event_size =
        kLcmLogHeaderSize + std::uint64_t{header.channel_length} + header.data_length;
    if (event_size > remaining) {
      return "event of " + std::to_string(event_size) + " bytes runs past the end of the file (" +
             std::to_string(remaining) + " bytes left)";
    }
    return std::nullopt;
  }

  // Offset of the first sync word strictly after `offset`, or the file size if there is none.
  std::uint64_t find_next_sync(std::uint64_t offset) {
    const std::uint64_t size = source->size();
    std::uint64_t start = offset + 1;
    while (start + kSyncBytes.size() <= size) {
      const auto n =
          static_cast<std::size_t>(std::min<std::uint64_t>(kScanChunkSize, size - start));
      // Grows once to the chunk size (or the file size, if smaller) and is then reused.
      if (scan_buffer.size() < n) scan_buffer.resize(n);
      const std::span<std::byte> chunk(scan_buffer.data(), n);
      source->read(start, chunk);
      const auto hit =
          std::search(chunk.begin(), chunk.end(), kSyncBytes.begin(), kSyncBytes.end());
      if (hit != chunk.end()) return start + static_cast<std::uint64_t>(hit - chunk.begin());
      // Overlap by three bytes so that a sync word split across two chunks is still found (the
      // loop condition guarantees n >= 4, so this always advances).
      start += n - (kSyncBytes.size() - 1);
    }
    return size;
  }

  std::optional<LcmLogEvent> next() {
    Header header{};
    while (true) {
      if (position >= source->size()) return std::nullopt;
      const auto problem = parse_header(position, header);
      if (!problem) break;
      if (options.on_corruption == LcmLogCorruption::kThrow) {
        throw FormatError(source_name, position, *problem);
      }
      const std::uint64_t resume = find_next_sync(position);
      ++stats.resyncs;
      stats.skipped_bytes += resume - position;
      position = resume;
    }
    body.resize(header.channel_length + header.data_length);
    source->read(position + kLcmLogHeaderSize, body);

    LcmLogEvent event;
    event.event_number = header.event_number;
    event.timestamp_us = header.timestamp_us;
    event.channel =
        std::string_view(reinterpret_cast<const char*>(body.data()), header.channel_length);
    event.data = std::span<const std::byte>(body).subspan(header.channel_length);
    event.offset = position;
    position += kLcmLogHeaderSize + body.size();
    ++stats.events;
    return event;
  }
};

LcmLogReader::LcmLogReader(const std::filesystem::path& path, LcmLogReaderOptions options)
    : impl_(std::make_unique<Impl>()) {
  impl_->source = std::make_unique<FileSource>(path);
  impl_->source_name = path.string();
  impl_->options = options;
}

LcmLogReader::LcmLogReader(std::unique_ptr<Impl> impl) : impl_(std::move(impl)) {}

LcmLogReader LcmLogReader::from_bytes(std::span<const std::byte> bytes, std::string source_name,
                                      LcmLogReaderOptions options) {
  auto impl = std::make_unique<Impl>();
  impl->source = std::make_unique<MemorySource>(bytes);
  impl->source_name = std::move(source_name);
  impl->options = options;
  return LcmLogReader(std::move(impl));
}

LcmLogReader::~LcmLogReader() = default;
LcmLogReader::LcmLogReader(LcmLogReader&&) noexcept = default;
LcmLogReader& LcmLogReader::operator=(LcmLogReader&&) noexcept = default;

std::optional<LcmLogEvent> LcmLogReader::next() {
  return impl_->next();
}
void LcmLogReader::rewind() {
  impl_->position = 0;
}
std::uint64_t LcmLogReader::size_bytes() const {
  return impl_->source->size();
}
const LcmLogStats& LcmLogReader::stats() const {
  return impl_->stats;
}

struct LcmLogWriter::Impl {
  std::string path;
  std::FILE* file = nullptr;
  LcmLogWriterOptions options;
  std::int64_t next_event_number = 0;

  ~Impl() {
    if (file != nullptr) std::fclose(file);
  }

  void require_open() const {
    if (file == nullptr) throw Error(path + ": LCM log writer is closed");
  }
};

LcmLogWriter::LcmLogWriter(const std::filesystem::path& path, LcmLogWriterOptions options)
    : impl_(std::make_unique<Impl>()) {
  impl_->path = path.string();
  impl_->options = options;
  if (options.append && std::filesystem::exists(path)) {
    // Continue the numbering of the existing log; reading it strictly also refuses to extend a
    // corrupt log.
    LcmLogReaderOptions reader_options;
    reader_options.max_channel_length =
        std::max(options.max_channel_length, kLcmLogDefaultMaxChannelLength);
    reader_options.max_data_length =
        static_cast<std::size_t>(std::numeric_limits<std::int32_t>::max());
    LcmLogReader reader(path, reader_options);
    while (const auto event = reader.next()) {
      impl_->next_event_number = event->event_number + 1;
    }
  }
  impl_->file = std::fopen(impl_->path.c_str(), options.append ? "ab" : "wb");
  if (impl_->file == nullptr) {
    throw Error(impl_->path + ": cannot open LCM log for writing: " + errno_text());
  }
}

LcmLogWriter::~LcmLogWriter() = default;
LcmLogWriter::LcmLogWriter(LcmLogWriter&&) noexcept = default;
LcmLogWriter& LcmLogWriter::operator=(LcmLogWriter&&) noexcept = default;

std::int64_t LcmLogWriter::write(std::int64_t timestamp_us, std::string_view channel,
                                 std::span<const std::byte> data) {
  impl_->require_open();
  if (channel.empty() || channel.size() > impl_->options.max_channel_length) {
    throw Error(impl_->path + ": LCM channel name length " + std::to_string(channel.size()) +
                " out of range [1, " + std::to_string(impl_->options.max_channel_length) + "]");
  }
  if (data.size() > static_cast<std::size_t>(std::numeric_limits<std::int32_t>::max())) {
    throw Error(impl_->path + ": LCM event data of " + std::to_string(data.size()) +
                " bytes exceeds the format's 2^31-1 limit");
  }
  const std::int64_t event_number = impl_->next_event_number;
  std::array<std::byte, kLcmLogHeaderSize> header{};
  store_be32(header.data(), kLcmLogSyncWord);
  store_be64(header.data() + 4, static_cast<std::uint64_t>(event_number));
  store_be64(header.data() + 12, static_cast<std::uint64_t>(timestamp_us));
  store_be32(header.data() + 20, static_cast<std::uint32_t>(channel.size()));
  store_be32(header.data() + 24, static_cast<std::uint32_t>(data.size()));
  const bool ok =
      std::fwrite(header.data(), 1, header.size(), impl_->file) == header.size() &&
      std::fwrite(channel.data(), 1, channel.size(), impl_->file) == channel.size() &&
      (data.empty() || std::fwrite(data.data(), 1, data.size(), impl_->file) == data.size());
  if (!ok) throw Error(impl_->path + ": write error: " + errno_text());
  ++impl_->next_event_number;
  return event_number;
}

void LcmLogWriter::flush() {
  impl_->require_open();
  if (std::fflush(impl_->file) != 0) throw Error(impl_->path + ": flush error: " + errno_text());
}

void LcmLogWriter::close() {
  impl_->require_open();
  std::FILE* file = std::exchange(impl_->file, nullptr);
  if (std::fclose(file) != 0) throw Error(impl_->path + ": close error: " + errno_text());
}

std::int64_t LcmLogWriter::next_event_number() const {
  return impl_->next_event_number;
}

}  // namespace livod::io
