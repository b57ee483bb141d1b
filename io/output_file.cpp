#include "io/output_file.hpp"

#include <cerrno>
#include <cstdio>
#include <cstring>

#include "core/error.hpp"

namespace livod::io {
namespace {

std::string reason(int err) {
  return err != 0 ? std::strerror(err) : "I/O error";
}

}  // namespace

OutputFile::OutputFile(std::filesystem::path path, bool binary) : path_(std::move(path)) {
  errno = 0;
  out_.open(partial_path(),
            std::ios::out | std::ios::trunc | (binary ? std::ios::binary : std::ios::out));
  if (!out_) throw Error("cannot create " + partial_path().string() + ": " + reason(errno));
}

std::filesystem::path OutputFile::partial_path() const {
  std::filesystem::path p = path_;
  p += ".partial";
  return p;
}

void OutputFile::commit() {
  if (committed_) return;
  errno = 0;
  out_.flush();
  const bool ok = static_cast<bool>(out_);
  const int err = errno;
  out_.close();
  if (!ok || out_.fail()) {
    std::error_code ec;
    std::filesystem::remove(partial_path(), ec);
    throw Error("cannot write " + path_.string() + ": " + reason(err));
  }
  if (std::rename(partial_path().c_str(), path_.c_str()) != 0) {
    const int rerr = errno;
    throw Error("cannot write " + path_.string() + ": rename from " + partial_path().string() +
                ": " + reason(rerr));
  }
  committed_ = true;
}

void write_file(const std::filesystem::path& path, std::string_view contents) {
  OutputFile f(path);
  f.stream().write(contents.data(), static_cast<std::streamsize>(contents.size()));
  f.commit();
}

}  // namespace livod::io
