#pragma once
// PCD v0.7 files (the header PCL and CloudCompare read), without PCL: the header for a list of
// fields, and a whole x y z file. Used by `livod decode` (drivers/scan_writer) and `livod replay`
// (the map).

#include <cstdint>
#include <filesystem>
#include <string>
#include <string_view>
#include <vector>

namespace livod::io {

struct PcdField {
  std::string_view name;
  int size = 4;     // bytes
  char type = 'F';  // F float, U unsigned, I signed
};

// The header of an unorganised (HEIGHT 1) cloud of `points` points, ending with the DATA line.
// count_width > 0 right-aligns WIDTH and POINTS in that many columns, so that a writer that
// learns the count at the end can rewrite the header in place (PCD readers split header lines on
// any whitespace).
[[nodiscard]] std::string pcd_header(const std::vector<PcdField>& fields, std::uint64_t points,
                                     bool binary, const std::string& comment = {},
                                     int count_width = 0);

// x y z float32 points (xyz.size() / 3 of them) as a binary PCD, written as NAME.partial and
// renamed when complete (io/output_file.hpp). Throws livod::Error if the file cannot be written.
void write_pcd_xyz(const std::filesystem::path& path, const std::vector<float>& xyz);

}  // namespace livod::io
