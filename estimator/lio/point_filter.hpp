#pragma once
// lio.point_filter_num: keep about one point in n of a scan, chosen by the point itself.
//
// Every n-th point of the scan keeps only the rings whose index shares n's factors (scans
// interleave their rings: Velodyne firings, Ouster columns, Livox lines); every n-th point of each
// ring keeps all rings but which points it keeps depends on where the ring's count starts, i.e. on
// where the scan was cut and in which order the packets came, and so a bag and a pcap of the same
// drive kept different points. A hash of the point's quantised coordinates keeps one point in n of
// every ring, every surface and every part of the scan alike, and the same point whatever its
// position in the scan, its time stamp or the container it came in.

#include <Eigen/Core>
#include <cstdint>

#include "core/hash_mix.hpp"
#include "estimator/grid_index.hpp"

namespace livod::estimator {

// The quantum of the coordinates hashed (1 mm: points of one ring are further apart than that
// except at a few centimetres' range, inside any blind distance).
inline constexpr double kPointFilterQuantumM = 1e-3;

// True for the points point_filter_num = n keeps (all for n <= 1).
inline bool point_filter_keeps(const Eigen::Vector3f& p, std::uint32_t n) {
  if (n <= 1) return true;
  constexpr double kInv = 1.0 / kPointFilterQuantumM;
  const auto q = [](float v) {
    return static_cast<std::uint64_t>(floor_to_int(static_cast<double>(v) * kInv + 0.5)) & 0x1FFFFF;
  };
  const std::uint64_t key = (q(p.x()) << 42) | (q(p.y()) << 21) | q(p.z());
  return hash_mix(key) % n == 0;
}

}  // namespace livod::estimator
