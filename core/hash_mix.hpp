#pragma once
// The splitmix64 finaliser: spreads integer keys that differ in few bits (packed lattice
// coordinates of voxels and cells) over all 64 bits, for open-addressing tables indexed by the
// low bits.

#include <cstdint>

namespace livod {

inline std::uint64_t hash_mix(std::uint64_t k) {
  k ^= k >> 30;
  k *= 0xbf58476d1ce4e5b9ULL;
  k ^= k >> 27;
  k *= 0x94d049bb133111ebULL;
  k ^= k >> 31;
  return k;
}

}  // namespace livod
