#include "drivers/imu/imu_decoder.hpp"

#include <fmt/core.h>

namespace livod::imu {

ImuDecoderCounters sum(const ImuDecoderCounters& a, const ImuDecoderCounters& b) {
  ImuDecoderCounters s;
  s.frames = a.frames + b.frames;
  s.bytes = a.bytes + b.bytes;
  s.samples = a.samples + b.samples;
  s.malformed = a.malformed + b.malformed;
  s.checksum_errors = a.checksum_errors + b.checksum_errors;
  s.incomplete = a.incomplete + b.incomplete;
  s.sequence_gaps = a.sequence_gaps + b.sequence_gaps;
  s.counter_wraps = a.counter_wraps + b.counter_wraps;
  s.invalid = a.invalid + b.invalid;
  s.saturated = a.saturated + b.saturated;
  s.skipped_bytes = a.skipped_bytes + b.skipped_bytes;
  return s;
}

std::string format_counters(const ImuDecoderCounters& c) {
  std::string out = fmt::format(
      "frames {}, samples {}, malformed {}, checksum errors {}, incomplete {}, gaps {}, "
      "invalid {}, saturated {}, counter wraps {}",
      c.frames, c.samples, c.malformed, c.checksum_errors, c.incomplete, c.sequence_gaps, c.invalid,
      c.saturated, c.counter_wraps);
  if (c.bytes > 0) out += fmt::format(", bytes {} (skipped {})", c.bytes, c.skipped_bytes);
  return out;
}

}  // namespace livod::imu
