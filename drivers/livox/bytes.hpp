#pragma once
// Little-endian field access on byte spans for the Livox wire formats. Callers check lengths
// before reading; these helpers do no bounds checks of their own.

#include <cstddef>
#include <cstdint>
#include <cstring>
#include <span>
#include <vector>

#include "core/little_endian.hpp"

namespace livod::livox {

template <class T>
T read_le(std::span<const std::byte> data, std::size_t offset) {
  return load_le<T>(data.data() + offset);
}

template <class T>
void append_le(std::vector<std::byte>& out, T value) {
  const auto* p = reinterpret_cast<const std::byte*>(&value);
  out.insert(out.end(), p, p + sizeof(T));
}

template <class T>
void write_le(std::span<std::byte> out, std::size_t offset, T value) {
  std::memcpy(out.data() + offset, &value, sizeof(T));
}

}  // namespace livod::livox
