#pragma once
// livod serial capture: the bytes a serial / USB IMU sent, in the chunks the host read them, each
// with its receive time, so that a recorded stream replays through a StreamImuDecoder exactly as
// the live reads did (torn messages included). The simulator writes it (SerialCaptureWriter);
// `livod record` writes it from the live source's reads (serial_capture_header() and
// append_serial_record() into its blocks, daemon/record/recorder.hpp).
//
// Layout (all little-endian):
//   header  8 bytes  "LVSERCAP"
//           u32      version (1)
//           u32      reserved (0)
//   record  i64      rx_time_ns   host receive time of the read (CLOCK_MONOTONIC live; the
//                                  simulator's host clock)
//           u32      length       bytes of this read, 1 .. kMaxChunkBytes
//           u8[length]
// Records are in receive order. A truncated last record, a bad header or an impossible length
// raises livod::FormatError with the byte offset.

#include <cstddef>
#include <cstdint>
#include <filesystem>
#include <fstream>
#include <memory>
#include <span>
#include <string>
#include <string_view>
#include <vector>

namespace livod::io {

struct SerialChunk {
  std::int64_t rx_time_ns = 0;
  std::vector<std::byte> bytes;  // capacity reused by the reader
};

// The file header (16 bytes), and one record appended to `out`: what SerialCaptureWriter writes,
// for writers that collect records into blocks of their own. append_serial_record() throws
// std::invalid_argument for an empty read or one above SerialCaptureReader::kMaxChunkBytes.
[[nodiscard]] std::vector<std::byte> serial_capture_header();
[[nodiscard]] constexpr std::size_t serial_record_bytes(std::size_t bytes) {
  return 12 + bytes;
}
void append_serial_record(std::vector<std::byte>& out, std::int64_t rx_time_ns,
                          std::span<const std::byte> bytes);

class SerialCaptureReader {
 public:
  static constexpr std::uint32_t kMaxChunkBytes = 1U << 20;

  // Throws livod::Error if the file cannot be opened, FormatError if the header is wrong.
  explicit SerialCaptureReader(const std::filesystem::path& path);
  // Reads capture bytes held in memory (copied); `name` appears in error messages.
  static SerialCaptureReader from_memory(std::string_view data, std::string name = "<memory>");
  ~SerialCaptureReader();
  SerialCaptureReader(SerialCaptureReader&&) noexcept;
  SerialCaptureReader& operator=(SerialCaptureReader&&) noexcept;

  // The next chunk; false at the end. Throws FormatError on a corrupt record.
  bool next(SerialChunk& chunk);
  [[nodiscard]] std::uint64_t chunks() const;
  [[nodiscard]] std::uint64_t bytes() const;

 private:
  struct Impl;
  explicit SerialCaptureReader(std::unique_ptr<Impl> impl);
  std::unique_ptr<Impl> impl_;
};

class SerialCaptureWriter {
 public:
  // Creates the file and writes the header; throws livod::Error if it cannot.
  explicit SerialCaptureWriter(const std::filesystem::path& path);
  // Appends one read (empty reads are skipped); throws std::invalid_argument above kMaxChunkBytes.
  void write(std::int64_t rx_time_ns, std::span<const std::byte> bytes);
  // Throws livod::Error if the data could not be written.
  void flush();

 private:
  std::string path_;
  std::ofstream out_;
};

}  // namespace livod::io
