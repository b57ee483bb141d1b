#pragma once
// The LiDAR points the visual update looks at. An image group holds the points measured since the
// previous update: with a camera faster than the LiDAR that is part of a sweep (half of it with a
// 20 Hz camera beside a 10 Hz LiDAR), and an image whose part lies behind the camera finds no
// visual voxel in view, so no visual point to track. RecentSweep keeps the registered points of
// the groups shorter than a scan period and joins those measured within one period of the current
// update to its points, so that every image looks at a whole sweep. A group holding a whole scan
// (camera at or below the LiDAR's rate) passes through as it is: nothing is copied.

#include <Eigen/Core>
#include <cstddef>
#include <deque>
#include <vector>

#include "core/time.hpp"
#include "estimator/map/plane.hpp"

namespace livod::estimator::vio {

class RecentSweep {
 public:
  struct View {
    const std::vector<CovPoint>* points;
    // Per point its plane normal (zero: none), or empty: none at all.
    const std::vector<Eigen::Vector3d>* normals;
  };

  // One group's registered points in the world and their normals (as View), measured in
  // (t_begin, t_end]; `period` is the LiDAR's scan period. Returns the sweep ending at t_end: these
  // points, after those of the earlier groups that began at most a period (plus a tenth, for
  // the jitter of image times) before t_end. The view is valid until the next call.
  View add(MappedTime t_begin, MappedTime t_end, Nanoseconds period,
           const std::vector<CovPoint>& points, const std::vector<Eigen::Vector3d>& normals);

  [[nodiscard]] std::size_t stored_points() const;

 private:
  struct Part {
    MappedTime t_begin;
    std::vector<CovPoint> points;
    std::vector<Eigen::Vector3d> normals;  // sized as points
  };
  static void append(const std::vector<CovPoint>& points,
                     const std::vector<Eigen::Vector3d>& normals, std::vector<CovPoint>& to_points,
                     std::vector<Eigen::Vector3d>& to_normals);

  std::deque<Part> parts_;  // time order; each shorter than a scan period
  std::vector<CovPoint> points_;
  std::vector<Eigen::Vector3d> normals_;
};

}  // namespace livod::estimator::vio
