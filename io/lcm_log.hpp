#pragma once
// LCM event logs: the file format that lcm-logger writes and lcm-logplayer plays (LCM docs, "LCM
// Log File format"). A log is a sequence of events; each event is a 28-byte big-endian header
//   u32 sync word 0xEDA1DA01 | i64 event number | i64 timestamp (µs since the UNIX epoch)
//   | i32 channel length | i32 data length
// followed by the channel name (no terminating NUL) and the message bytes.
//
// Corruption policy (see docs/io-formats.md): by default the reader is strict and throws
// livod::FormatError with the byte offset of the bad event. With LcmLogCorruption::kResync it
// scans forward to the next sync word (what LCM's own reader does), counts the skipped bytes and
// carries on; a truncated final event then simply ends the log. Every length is checked against
// the bytes left in the file and against explicit limits before anything is allocated.

#include <cstddef>
#include <cstdint>
#include <filesystem>
#include <memory>
#include <optional>
#include <span>
#include <string>
#include <string_view>

namespace livod::io {

inline constexpr std::uint32_t kLcmLogSyncWord = 0xEDA1DA01;
inline constexpr std::size_t kLcmLogHeaderSize = 28;
// LCM limits channel names to 63 bytes on the wire; logs from other writers get some slack, but a
// bogus length must not turn into a huge string.
inline constexpr std::size_t kLcmLogDefaultMaxChannelLength = 1024;
inline constexpr std::size_t kLcmLogDefaultMaxDataLength = std::size_t{256} << 20;

// One event as read from a log. `channel` and `data` point into the reader's buffer and are valid
// until the next call to next() or rewind().
struct LcmLogEvent {
  std::int64_t event_number = 0;
  std::int64_t timestamp_us = 0;  // receive time, µs since the UNIX epoch (as lcm-logger writes)
  std::string_view channel;
  std::span<const std::byte> data;
  std::uint64_t offset = 0;  // byte offset of the event header in the log
};

enum class LcmLogCorruption {
  kThrow,   // throw livod::FormatError at the first bad event (default)
  kResync,  // skip to the next sync word, count what was skipped
};

struct LcmLogReaderOptions {
  LcmLogCorruption on_corruption = LcmLogCorruption::kThrow;
  std::size_t max_channel_length = kLcmLogDefaultMaxChannelLength;
  std::size_t max_data_length = kLcmLogDefaultMaxDataLength;
};

struct LcmLogStats {
  std::uint64_t events = 0;         // events returned by next()
  std::uint64_t resyncs = 0;        // bad spots skipped in kResync mode
  std::uint64_t skipped_bytes = 0;  // bytes skipped while resynchronising (incl. a truncated tail)
};

class LcmLogReader {
 public:
  // Opens a log file. Throws livod::Error with the path if it cannot be opened.
  explicit LcmLogReader(const std::filesystem::path& path, LcmLogReaderOptions options = {});
  // Reads a log held in memory (fuzzing, tests). `bytes` must outlive the reader; `source_name`
  // appears in error messages in place of a path.
  static LcmLogReader from_bytes(std::span<const std::byte> bytes, std::string source_name,
                                 LcmLogReaderOptions options = {});
  ~LcmLogReader();
  LcmLogReader(LcmLogReader&&) noexcept;
  LcmLogReader& operator=(LcmLogReader&&) noexcept;
  LcmLogReader(const LcmLogReader&) = delete;
  LcmLogReader& operator=(const LcmLogReader&) = delete;

  // The next event, or nullopt at the end of the log. In kThrow mode a bad sync word, a length out
  // of range or an event cut short by the end of the file throws livod::FormatError (offset = the
  // event header); an I/O error throws livod::Error.
  std::optional<LcmLogEvent> next();

  // Back to the first event (stats are kept).
  void rewind();

  [[nodiscard]] std::uint64_t size_bytes() const;
  [[nodiscard]] const LcmLogStats& stats() const;

 private:
  struct Impl;
  explicit LcmLogReader(std::unique_ptr<Impl> impl);
  std::unique_ptr<Impl> impl_;
};

struct LcmLogWriterOptions {
  // Append to an existing log, continuing its event numbers (the existing log is read strictly
  // first, so a corrupt log throws instead of being extended). A missing file is created.
  bool append = false;
  std::size_t max_channel_length = kLcmLogDefaultMaxChannelLength;
};

// Writes events with event numbers 0, 1, 2, ... (or continuing an appended log). Timestamps are
// written as given; LCM expects them to increase, which the caller owns.
class LcmLogWriter {
 public:
  // Creates (truncates) or appends to `path`. Throws livod::Error if it cannot be opened.
  explicit LcmLogWriter(const std::filesystem::path& path, LcmLogWriterOptions options = {});
  ~LcmLogWriter();  // closes without reporting errors; call close() to see them
  LcmLogWriter(LcmLogWriter&&) noexcept;
  LcmLogWriter& operator=(LcmLogWriter&&) noexcept;
  LcmLogWriter(const LcmLogWriter&) = delete;
  LcmLogWriter& operator=(const LcmLogWriter&) = delete;

  // Appends one event and returns its event number. Throws livod::Error for an empty or too long
  // channel, data longer than INT32_MAX bytes, a write error, or after close().
  std::int64_t write(std::int64_t timestamp_us, std::string_view channel,
                     std::span<const std::byte> data);

  void flush();
  // Flushes and closes; throws livod::Error if the data could not be written.
  void close();

  [[nodiscard]] std::int64_t next_event_number() const;

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace livod::io
