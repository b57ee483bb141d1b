#pragma once
// can-utils "compact" log files, as written by `candump -l` and read by canplayer/log2asc:
//
//   (1436509052.249713) can0 123#DEADBEEF          classic frame, 11-bit id (3 hex digits)
//   (1436509052.249713) can0 12345678#0011         classic frame, 29-bit id (8 hex digits)
//   (1436509052.249713) can0 123#R  /  123#R5      remote request, optional DLC digit 0-8
//   (1436509052.249713) can0 123##1DEADBEEF        CAN FD: '##', one flags nibble, up to 64 bytes
//   (1436509052.249713) can0 20000080#0000000000000000   error frame (CAN_ERR_FLAG in the id)
//   (1436509052.249713) can0 123#1122334455667788_E      classic frame with raw DLC 9..15
//   (1436509052.249713) can0 123#DEADBEEF R        candump -x direction suffix (R or T)
//
// Data bytes may be separated by '.'; the interface may be right-aligned with extra spaces.
// Timestamps have 6 fractional digits (microseconds); 9 digits (nanoseconds) are also read.
// Blank lines are skipped. Anything else that does not parse raises livod::FormatError naming the
// line number and byte offset, or, in lenient mode, is skipped and counted.

#include <array>
#include <cstddef>
#include <cstdint>
#include <filesystem>
#include <fstream>
#include <memory>
#include <optional>
#include <string>
#include <string_view>

#include "io/input_loss.hpp"

namespace livod::io {

struct CanFrame {
  std::int64_t time_ns = 0;   // log timestamp (UTC epoch ns; the log resolution is 1 us)
  std::string interface;      // e.g. "can0" (Linux names are at most 15 bytes: no allocation)
  std::uint32_t id = 0;       // 11- or 29-bit identifier; for error frames the error class bits
  bool extended = false;      // 29-bit identifier (8 hex digits in the log)
  bool rtr = false;           // remote transmission request (classic CAN only)
  bool fd = false;            // CAN FD frame
  bool error = false;         // error frame (CAN_ERR_FLAG); `id` holds the error class mask
  std::uint8_t fd_flags = 0;  // CAN FD flags nibble (bit 0 BRS, bit 1 ESI)
  std::uint8_t len8_dlc = 0;  // classic CAN raw DLC 9..15 when the log gives one, else 0
  char direction = 0;         // 'R' or 'T' from `candump -x`, 0 when absent
  std::uint8_t len = 0;       // payload bytes (for RTR: the requested DLC)
  std::array<std::uint8_t, 64> data{};

  friend bool operator==(const CanFrame&, const CanFrame&) = default;
};

// Why a line does not parse: a message and the column (0-based byte within the line).
struct CandumpParseError {
  std::string message;
  std::size_t column = 0;
};

// Parses one log line (without the newline). Returns the error instead of throwing, so that the
// reader can add the line number and file offset. `frame` is overwritten (its interface string
// keeps its capacity) and is unspecified on error.
std::optional<CandumpParseError> parse_candump_line(std::string_view line, CanFrame& frame);

// Formats one frame as a log line without the newline, exactly as candump writes it (upper-case
// hex, no data separators, 6 fractional digits: sub-microsecond time is truncated). Throws
// std::invalid_argument for a frame candump could not have written (id out of range, RTR on an FD
// frame, length above 8 / 64, empty interface or one containing whitespace, negative time).
std::string format_candump_line(const CanFrame& frame);

struct CandumpStats {
  std::uint64_t lines = 0;    // lines read, including blank and skipped ones
  std::uint64_t frames = 0;   // frames returned
  std::uint64_t skipped = 0;  // malformed lines skipped (lenient mode only)
};

struct CandumpReaderOptions {
  bool lenient = false;  // skip and count malformed lines instead of throwing
};

class CandumpReader {
 public:
  using Options = CandumpReaderOptions;

  // Throws livod::Error if the file cannot be opened.
  explicit CandumpReader(const std::filesystem::path& path, Options options = {});
  // Reads log text held in memory (copied); `name` appears in error messages.
  static CandumpReader from_memory(std::string_view text, std::string name = "<memory>",
                                   Options options = {});
  ~CandumpReader();
  CandumpReader(CandumpReader&&) noexcept;
  CandumpReader& operator=(CandumpReader&&) noexcept;
  CandumpReader(const CandumpReader&) = delete;
  CandumpReader& operator=(const CandumpReader&) = delete;

  // Fills `frame` with the next frame; false at the end of the input. Throws livod::FormatError
  // ("<source>: at byte offset N: line L, column C: ...") on a malformed line unless lenient.
  bool next(CanFrame& frame);

  [[nodiscard]] const CandumpStats& stats() const;
  // The first skipped line's error in lenient mode (same text FormatError would carry), or empty.
  [[nodiscard]] const std::string& first_skipped_error() const;
  // Lenient mode: the skipped lines, consecutive ones as one loss (byte offset, bytes, lines, and
  // the log time between the frames around them). Complete once next() has returned false.
  [[nodiscard]] const InputLossLog& losses() const;

 private:
  struct Impl;
  explicit CandumpReader(std::unique_ptr<Impl> impl);
  std::unique_ptr<Impl> impl_;
};

class CandumpWriter {
 public:
  // Throws livod::Error if the file cannot be created.
  explicit CandumpWriter(const std::filesystem::path& path);
  // Appends one line; throws std::invalid_argument (see format_candump_line).
  void write(const CanFrame& frame);
  // Throws livod::Error if the data could not be written.
  void flush();

 private:
  std::string source_;
  std::ofstream out_;
  std::string line_;
};

}  // namespace livod::io
