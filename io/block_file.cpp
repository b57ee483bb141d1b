#include "io/block_file.hpp"

#include <fcntl.h>
#include <unistd.h>

#include <cerrno>
#include <cstring>
#include <utility>

#include "core/error.hpp"

namespace livod::io {

BlockFile::BlockFile(const std::filesystem::path& path) : path_(path) {
  fd_ = ::open(path.c_str(), O_WRONLY | O_CREAT | O_TRUNC | O_CLOEXEC, 0644);
  if (fd_ < 0) throw Error("cannot create " + path.string() + ": " + std::strerror(errno));
}

BlockFile::~BlockFile() {
  close();
}

BlockFile::BlockFile(BlockFile&& other) noexcept
    : path_(std::move(other.path_)), fd_(std::exchange(other.fd_, -1)), size_(other.size_) {}

BlockFile& BlockFile::operator=(BlockFile&& other) noexcept {
  if (this != &other) {
    close();
    path_ = std::move(other.path_);
    fd_ = std::exchange(other.fd_, -1);
    size_ = other.size_;
  }
  return *this;
}

int BlockFile::append(std::span<const std::byte> block) {
  if (fd_ < 0) return EBADF;
  std::size_t done = 0;
  while (done < block.size()) {
    const ssize_t n =
        ::pwrite(fd_, block.data() + done, block.size() - done, static_cast<off_t>(size_ + done));
    if (n < 0 && errno == EINTR) continue;
    if (n <= 0) {
      const int err = n < 0 ? errno : ENOSPC;
      // Cut the partial block off: the file ends with the previous complete block again.
      if (done > 0) {
        while (::ftruncate(fd_, static_cast<off_t>(size_)) != 0 && errno == EINTR) {
        }
      }
      return err;
    }
    done += static_cast<std::size_t>(n);
  }
  size_ += block.size();
  return 0;
}

int BlockFile::sync() {
  if (fd_ < 0) return EBADF;
  return ::fdatasync(fd_) == 0 ? 0 : errno;
}

int BlockFile::close() {
  if (fd_ < 0) return 0;
  int err = ::fdatasync(fd_) == 0 ? 0 : errno;
  if (::close(fd_) != 0 && err == 0) err = errno;
  fd_ = -1;
  return err;
}

}  // namespace livod::io
