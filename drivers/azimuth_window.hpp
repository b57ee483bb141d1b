#pragma once
// A spinning LiDAR's configured azimuth window (Velodyne "FOV start/end", Hesai start/end angle):
// the sensor sends only the azimuths from start to end, clockwise, wrapping through 0 when start
// > end. The rest is a skipped sector: time passes there, but no packet was due, so a decoder
// must not count it as loss.

#include <algorithm>
#include <cmath>

namespace livod::drivers {

struct AzimuthWindow {
  double start_deg = 0.0;
  double end_deg = 360.0;

  // Length of the skipped sector [end, start) in 0.01 degree (0 for a full turn).
  [[nodiscard]] int skipped_length_centideg() const {
    const int start = static_cast<int>(std::lround(start_deg * 100.0)) % 36000;
    const int end = static_cast<int>(std::lround(end_deg * 100.0)) % 36000;
    return (36000 + start - end) % 36000;
  }

  // How much of the clockwise path from azimuth `from` to `to` (0.01 degree) lies in the skipped
  // sector.
  [[nodiscard]] int skipped_on_path_centideg(int from, int to) const {
    const int length = skipped_length_centideg();
    if (length == 0) return 0;
    const int gap_begin = static_cast<int>(std::lround(end_deg * 100.0)) % 36000;
    const int path = ((to - from) % 36000 + 36000) % 36000;
    const int into_gap = ((gap_begin - from) % 36000 + 36000) % 36000;
    if (into_gap >= path) return 0;
    return std::min(length, path - into_gap);
  }
};

}  // namespace livod::drivers
