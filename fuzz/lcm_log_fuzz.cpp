// libFuzzer target: the LCM event log reader on arbitrary bytes, in both corruption policies.
// Invariants checked: no crash or sanitizer report, only livod::FormatError escapes strict mode,
// nothing escapes resync mode, and every returned event lies inside the input.

#include <cstddef>
#include <cstdint>
#include <cstdlib>
#include <span>

#include "core/error.hpp"
#include "io/lcm_log.hpp"

namespace {

void check_events(livod::io::LcmLogReader& reader, std::span<const std::byte> bytes) {
  std::uint64_t previous_end = 0;
  while (const auto event = reader.next()) {
    const std::uint64_t end =
        event->offset + livod::io::kLcmLogHeaderSize + event->channel.size() + event->data.size();
    // Events come in file order, do not overlap, and stay inside the input.
    if (event->offset < previous_end || end > bytes.size() || event->channel.empty()) std::abort();
    previous_end = end;
  }
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const std::span<const std::byte> bytes(reinterpret_cast<const std::byte*>(data), size);
  // Small limits so that the length checks are exercised by short inputs too.
  livod::io::LcmLogReaderOptions options;
  options.max_channel_length = 64;
  options.max_data_length = 4096;

  auto strict = livod::io::LcmLogReader::from_bytes(bytes, "fuzz", options);
  try {
    check_events(strict, bytes);
  } catch (const livod::FormatError& e) {
    if (e.offset() >= size) std::abort();  // the offset must point into the input
  }

  options.on_corruption = livod::io::LcmLogCorruption::kResync;
  auto tolerant = livod::io::LcmLogReader::from_bytes(bytes, "fuzz", options);
  check_events(tolerant, bytes);
  const auto& stats = tolerant.stats();
  if (stats.skipped_bytes > size) std::abort();
  return 0;
}
