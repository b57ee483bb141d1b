#pragma once
// Error types shared by every module. Readers of recorded files throw FormatError with the byte
// offset where the problem was found; decoders of live packets never throw (they return a status
// and bump a counter, see the drivers).

#include <cstdint>
#include <stdexcept>
#include <string>

namespace livod {

class Error : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

// A corrupt or truncated file/stream. what() already contains the offset and the source.
class FormatError : public Error {
 public:
  FormatError(const std::string& source, std::uint64_t offset, const std::string& message)
      : Error(source + ": at byte offset " + std::to_string(offset) + ": " + message),
        offset_(offset) {}
  [[nodiscard]] std::uint64_t offset() const { return offset_; }

 private:
  std::uint64_t offset_;
};

}  // namespace livod
