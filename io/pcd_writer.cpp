#include "io/pcd_writer.hpp"

#include <cinttypes>
#include <cstdio>

#include "io/output_file.hpp"

namespace livod::io {

std::string pcd_header(const std::vector<PcdField>& fields, std::uint64_t points, bool binary,
                       const std::string& comment, int count_width) {
  std::string fields_line = "FIELDS";
  std::string size_line = "SIZE";
  std::string type_line = "TYPE";
  std::string count_line = "COUNT";
  for (const PcdField& f : fields) {
    fields_line += ' ';
    fields_line += f.name;
    size_line += ' ' + std::to_string(f.size);
    type_line += ' ';
    type_line += f.type;
    count_line += " 1";
  }
  char count[64];
  std::snprintf(count, sizeof count, "%*" PRIu64, count_width, points);
  std::string h = "# .PCD v0.7 - Point Cloud Data file format";
  if (!comment.empty()) h += " (" + comment + ")";
  h += "\nVERSION 0.7\n" + fields_line + "\n" + size_line + "\n" + type_line + "\n" + count_line +
       "\nWIDTH " + count + "\nHEIGHT 1\nVIEWPOINT 0 0 0 1 0 0 0\nPOINTS " + count +
       (binary ? "\nDATA binary\n" : "\nDATA ascii\n");
  return h;
}

void write_pcd_xyz(const std::filesystem::path& path, const std::vector<float>& xyz) {
  const std::size_t n = xyz.size() / 3;
  OutputFile file(path, true);
  std::ostream& out = file.stream();
  out << pcd_header({{"x"}, {"y"}, {"z"}}, n, true);
  // PCD binary data is the points' memory layout: little-endian float32 on every host livod
  // runs on.
  out.write(reinterpret_cast<const char*>(xyz.data()),
            static_cast<std::streamsize>(n * 3 * sizeof(float)));
  file.commit();
}

}  // namespace livod::io
