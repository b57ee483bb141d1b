#pragma once
// An output file that appears under its name only once it is complete: it is written as
// NAME.partial and renamed to NAME by commit(). A crash, a kill or a full disk leaves NAME.partial
// (with what was written so far), never a truncated NAME that looks complete. Errors name the file
// and the operating system's reason ("No space left on device").

#include <filesystem>
#include <fstream>
#include <string>
#include <string_view>

namespace livod::io {

class OutputFile {
 public:
  // Creates NAME.partial (throws livod::Error naming it and the reason).
  explicit OutputFile(std::filesystem::path path, bool binary = false);
  // Without commit() the partial file stays (the work so far, under a name that says so).
  ~OutputFile() = default;
  OutputFile(const OutputFile&) = delete;
  OutputFile& operator=(const OutputFile&) = delete;

  [[nodiscard]] std::ostream& stream() { return out_; }
  [[nodiscard]] const std::filesystem::path& path() const { return path_; }
  [[nodiscard]] std::filesystem::path partial_path() const;

  // Flushes, checks that everything was written and renames NAME.partial to NAME. Throws
  // livod::Error("cannot write NAME: <reason>") otherwise; the partial file is then removed.
  void commit();

 private:
  std::filesystem::path path_;
  std::ofstream out_;
  bool committed_ = false;
};

// Writes `contents` to `path` through an OutputFile.
void write_file(const std::filesystem::path& path, std::string_view contents);

}  // namespace livod::io
