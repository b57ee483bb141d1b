#pragma once
// Writes decoded scans to a CSV or PCD (v0.7) file, for `livod decode` and for inspecting
// captures with other tools. Points are in the LiDAR frame (x forward, y left, z up, metres).
//
// CSV: header `frame,x,y,z,intensity,t_ns,ring,return`, one row per valid point. `frame` counts
// the scans written, from 0, in file order (a partial first scan included); t_ns is the absolute
// point time in ns on the sensor timeline (Stamp::sensor of the scan + the point's offset).
//
// PCD: one cloud holding every valid point of every scan, fields `x y z intensity t ring`
// (F4 F4 F4 F4 F8 U2), t = the same absolute sensor time in seconds. Binary or ASCII. The point
// count is written into the header when the file is closed. No PCL involved.

#include <cstdint>
#include <filesystem>
#include <fstream>
#include <optional>
#include <string>

#include "core/measurement.hpp"

namespace livod::drivers {

enum class ScanFileFormat : std::uint8_t { kCsv, kPcdBinary, kPcdAscii };

// From the extension: ".csv" -> CSV, ".pcd" -> binary PCD (ASCII if `pcd_ascii`).
[[nodiscard]] std::optional<ScanFileFormat> scan_format_for(const std::filesystem::path& path,
                                                            bool pcd_ascii = false);

class ScanWriter {
 public:
  // Throws livod::Error if the file cannot be created.
  ScanWriter(const std::filesystem::path& path, ScanFileFormat format);
  ~ScanWriter();  // closes; errors are swallowed (call close() to see them)
  ScanWriter(const ScanWriter&) = delete;
  ScanWriter& operator=(const ScanWriter&) = delete;

  void write(const LidarScan& scan);
  // Completes the file (the PCD header's point count). Throws livod::Error on I/O failure.
  void close();

  [[nodiscard]] std::uint64_t scans_written() const { return scans_; }
  [[nodiscard]] std::uint64_t points_written() const { return points_; }

 private:
  void write_pcd_header(std::uint64_t points);

  std::filesystem::path path_;
  ScanFileFormat format_;
  std::ofstream out_;
  std::string buffer_;  // formatted text or packed records, flushed per scan
  std::uint64_t scans_ = 0;
  std::uint64_t points_ = 0;
  bool closed_ = false;
};

}  // namespace livod::drivers
