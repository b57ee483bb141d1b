#pragma once
// Small integer helpers shared by the decoders and the scan assemblers.

#include <cstdint>

namespace livod {

// Floor of a / b for b != 0 (C++ division truncates toward zero): the index of the interval of
// length b that holds a, also for negative a.
[[nodiscard]] constexpr std::int64_t floor_div(std::int64_t a, std::int64_t b) {
  const std::int64_t q = a / b;
  return (a % b != 0 && (a < 0) != (b < 0)) ? q - 1 : q;
}

}  // namespace livod
