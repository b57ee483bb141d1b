#pragma once
// Little-endian fields of sensor packets (Livox, Ouster), read with memcpy: the host must be
// little-endian too (checked at compile time). Callers check lengths; no bounds checks here.

#include <bit>
#include <cstddef>
#include <cstring>

namespace livod {

static_assert(std::endian::native == std::endian::little,
              "packet fields are read with memcpy from the little-endian wire formats");

// The T stored at p (no alignment needed).
template <class T>
T load_le(const std::byte* p) {
  T v{};
  std::memcpy(&v, p, sizeof(T));
  return v;
}

}  // namespace livod
