#pragma once
// A file that grows by whole blocks: each append() writes its block completely or not at all.
// When the disk is full (or any write fails) part-way through a block, the file is cut back to
// its size before the block, so what was written before stays a well-formed file whose last
// block is complete. A process killed during a write can leave at most the part of the block the
// kernel had taken; readers of livod's recordings tolerate such a tail (io/pcap.hpp reports it).
//
// For the recorder's IO thread (daemon/record/): it blocks in write(2) as long as the disk takes.

#include <cstddef>
#include <cstdint>
#include <filesystem>
#include <span>
#include <string>

namespace livod::io {

class BlockFile {
 public:
  // Creates the file (truncating one that exists). Throws livod::Error naming the file and the
  // reason.
  explicit BlockFile(const std::filesystem::path& path);
  ~BlockFile();
  BlockFile(BlockFile&& other) noexcept;
  BlockFile& operator=(BlockFile&& other) noexcept;
  BlockFile(const BlockFile&) = delete;
  BlockFile& operator=(const BlockFile&) = delete;

  // Appends `block` whole. Returns 0, or the errno of the failure (ENOSPC, EIO, ...) after the
  // file was cut back to its previous size. Never throws.
  int append(std::span<const std::byte> block);
  // fdatasync: what was appended survives a power loss. Returns 0 or errno.
  int sync();
  // Syncs and closes; returns 0 or the errno of the first failure. Idempotent.
  int close();

  [[nodiscard]] std::uint64_t size() const { return size_; }
  [[nodiscard]] const std::filesystem::path& path() const { return path_; }

 private:
  std::filesystem::path path_;
  int fd_ = -1;
  std::uint64_t size_ = 0;
};

}  // namespace livod::io
