#pragma once
// Ouster packets are little-endian; their fields are read with memcpy, so the host must be
// little-endian too (checked at compile time).

#include <bit>
#include <cstddef>
#include <cstring>

namespace livod::drivers::ouster {

static_assert(std::endian::native == std::endian::little,
              "Ouster packet fields are read with memcpy from the little-endian wire format");

// The T stored at p (no alignment needed).
template <class T>
T load(const std::byte* p) {
  T v{};
  std::memcpy(&v, p, sizeof(T));
  return v;
}

}  // namespace livod::drivers::ouster
