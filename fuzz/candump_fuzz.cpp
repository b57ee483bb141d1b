// libFuzzer target: the candump log parser. Every frame it accepts must format back to a line
// that parses to the same frame (time truncated to the microseconds the format keeps), in both
// lenient and strict mode.

#include <cstddef>
#include <cstdint>
#include <cstdlib>
#include <string_view>

#include "core/error.hpp"
#include "io/candump.hpp"

namespace {

void check_round_trip(const livod::io::CanFrame& frame) {
  // Throws (and so fails the run) if the parser accepted a frame the writer cannot express.
  const std::string line = livod::io::format_candump_line(frame);
  livod::io::CanFrame again;
  if (livod::io::parse_candump_line(line, again).has_value()) std::abort();
  livod::io::CanFrame expected = frame;
  expected.time_ns -= expected.time_ns % 1000;
  if (!(again == expected)) std::abort();
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const std::string_view text(reinterpret_cast<const char*>(data), size);

  livod::io::CanFrame frame;
  if (!livod::io::parse_candump_line(text, frame).has_value()) check_round_trip(frame);

  auto lenient = livod::io::CandumpReader::from_memory(text, "fuzz", {.lenient = true});
  std::uint64_t frames = 0;
  while (lenient.next(frame)) {
    check_round_trip(frame);
    ++frames;
  }
  if (lenient.stats().frames != frames) std::abort();

  auto strict = livod::io::CandumpReader::from_memory(text, "fuzz");
  try {
    std::uint64_t strict_frames = 0;
    while (strict.next(frame)) ++strict_frames;
    // Without an exception every line parsed, so lenient mode skipped nothing.
    if (strict_frames != frames || lenient.stats().skipped != 0) std::abort();
  } catch (const livod::FormatError&) {
    if (lenient.stats().skipped == 0) std::abort();
  }
  return 0;
}
