#pragma once
// Where a Hesai return lies: the beam of channel c at block azimuth A points at horizontal angle
// A + azimuth_c and vertical angle elevation_c (Hesai's angle correction file), with no
// interpolation within a block (Hesai's point cloud analysis). Hesai's frame has y forward, x
// right and the azimuth clockwise from y; livod's LiDAR frame is x forward, y left, z up:
//   x = d cos(el) cos(az),  y = -d cos(el) sin(az),  z = d sin(el).
// The decoder and the simulator share this, so that the simulator casts along the decoder's beams.

#include <cmath>
#include <cstdint>
#include <numbers>
#include <vector>

#include "core/units.hpp"
#include "drivers/hesai/calibration.hpp"

namespace livod::drivers::hesai {

struct BlockAngle {
  double cos_a = 1.0;
  double sin_a = 0.0;
};

[[nodiscard]] inline BlockAngle block_angle(std::uint16_t azimuth_centideg) {
  const double a = azimuth_centideg * (std::numbers::pi / 18000.0);
  return {std::cos(a), std::sin(a)};
}

class BeamGeometry {
 public:
  struct Channel {
    double cos_el, sin_el;
    double cos_az, sin_az;  // of the azimuth correction
  };

  explicit BeamGeometry(const AngleCorrections& corrections) {
    for (const ChannelCorrection& k : corrections.channels) {
      channels_.push_back(
          {std::cos(k.elevation_deg * kDegToRad), std::sin(k.elevation_deg * kDegToRad),
           std::cos(k.azimuth_deg * kDegToRad), std::sin(k.azimuth_deg * kDegToRad)});
    }
  }

  // The point at range d of channel c in a block at angle `block`, livod's LiDAR frame.
  void point(const BlockAngle& block, int channel, double d, double& x, double& y,
             double& z) const {
    const Channel& ch = channels_[static_cast<std::size_t>(channel)];
    const double cos_a = block.cos_a * ch.cos_az - block.sin_a * ch.sin_az;  // A + correction
    const double sin_a = block.sin_a * ch.cos_az + block.cos_a * ch.sin_az;
    const double xy = d * ch.cos_el;
    x = xy * cos_a;
    y = -xy * sin_a;
    z = d * ch.sin_el;
  }

  [[nodiscard]] std::size_t channels() const { return channels_.size(); }

 private:
  std::vector<Channel> channels_;
};

}  // namespace livod::drivers::hesai
