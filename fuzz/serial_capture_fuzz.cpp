// libFuzzer target: the livod serial capture reader. Any input either reads as records or throws
// livod::FormatError; the byte total matches the records read.

#include <cstddef>
#include <cstdint>
#include <cstdlib>
#include <string_view>

#include "core/error.hpp"
#include "io/serial_capture.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  try {
    auto reader = livod::io::SerialCaptureReader::from_memory(
        std::string_view(reinterpret_cast<const char*>(data), size), "fuzz");
    livod::io::SerialChunk chunk;
    std::uint64_t bytes = 0;
    while (reader.next(chunk)) {
      if (chunk.bytes.empty()) std::abort();
      bytes += chunk.bytes.size();
    }
    if (bytes != reader.bytes()) std::abort();
  } catch (const livod::FormatError&) {
  }
  return 0;
}
