#pragma once
// The visual map: points on LiDAR surfaces (position and normal from the LiDAR map's planes),
// each with a few reference patches, in a voxel hash that is bounded twice over:
//  - it slides with the LiDAR map (the same box and threshold, estimator.map), so a drive never
//    accumulates the world behind it (FAST-LIVO2 never prunes its visual map, defect 3);
//  - it holds at most max_visual_points; beyond that the points seen least recently go.
//
// A reference patch is what a point looked like in one image: for every pyramid level a small
// block of pixels around the point (the patch plus a two-pixel margin, so that the affine warp
// can rotate and scale it a little), the camera pose, the pixel and the inverse exposure of that
// image. No image is ever referenced (FAST-LIVO2 keeps every image a feature came from alive:
// about 2 GB per 4 GB bag).

#include <Eigen/Geometry>
#include <array>
#include <cstdint>
#include <unordered_map>
#include <vector>

#include "estimator/map/voxel_map.hpp"
#include "estimator/params.hpp"

namespace livod::estimator::vio {

inline constexpr int kMaxPyramidLevels = 6;

// Stored block edge for a patch edge: the patch plus a two-pixel margin on every side.
inline constexpr int block_edge(int patch_size) {
  return patch_size + 4;
}

struct PatchObservation {
  Eigen::Quaterniond q_world_cam = Eigen::Quaterniond::Identity();
  Eigen::Vector3d p_world_cam = Eigen::Vector3d::Zero();
  Eigen::Vector2d pixel = Eigen::Vector2d::Zero();  // level 0, where the point was seen
  float inv_exposure = 1.0F;                        // tau of that image
  float score = 0.0F;                               // reference score (last refresh)
  float ncc_sum = 0.0F;  // sum of |NCC| of its level-0 patch with the point's other patches
  // levels x block_edge^2 pixels, row-major per level; level l's block holds the integer pixels
  // around the point's level-l position, which sits at block_pos[l] inside it.
  std::vector<std::uint8_t> blocks;
  std::array<Eigen::Vector2f, kMaxPyramidLevels> block_pos{};

  [[nodiscard]] Eigen::Isometry3d T_world_cam() const {
    Eigen::Isometry3d T = Eigen::Isometry3d::Identity();
    T.linear() = q_world_cam.toRotationMatrix();
    T.translation() = p_world_cam;
    return T;
  }
  [[nodiscard]] const std::uint8_t* block(int level, int edge) const {
    return blocks.data() + static_cast<std::size_t>(level) * static_cast<std::size_t>(edge * edge);
  }
};

struct VisualPoint {
  Eigen::Vector3d p_world = Eigen::Vector3d::Zero();
  Eigen::Vector3d normal = Eigen::Vector3d::UnitZ();  // unit, towards the cameras that saw it
  std::vector<PatchObservation> observations;
  std::uint32_t reference = 0;  // index into observations
  std::uint64_t last_seen = 0;  // image counter when last tracked (or created)
  std::uint8_t failures = 0;    // images in a row it was selected but failed the photometric gate
  bool alive = false;
};

struct VisualMapStats {
  std::size_t points = 0;
  std::size_t voxels = 0;
  std::size_t observations = 0;
  std::size_t bytes = 0;  // points, patches and the voxel table (capacity): an estimate of heap use
  std::uint64_t created = 0;
  std::uint64_t removed_sliding = 0;  // left the sliding box
  std::uint64_t removed_budget = 0;   // evicted as least recently seen
};

class VisualMap {
 public:
  VisualMap(double voxel_size, const MapParams& map, std::size_t max_points);

  std::uint32_t add(VisualPoint point);
  void remove(std::uint32_t id);
  [[nodiscard]] VisualPoint& at(std::uint32_t id) { return points_[id]; }
  [[nodiscard]] const VisualPoint& at(std::uint32_t id) const { return points_[id]; }

  // The voxel of a world point.
  [[nodiscard]] VoxelKey key(const Eigen::Vector3d& p) const { return voxel_key(p, voxel_size_); }
  // Ids of the points in the voxels `keys` name, each once, in the order of the keys; a key met
  // again shortly after costs no lookup (scans arrive in spatial order).
  void gather(const std::vector<VoxelKey>& keys, std::vector<std::uint32_t>& ids);

  // Drops the voxels outside the LiDAR map's box once the sensor moved slide_threshold since the
  // last slide (the LiDAR map's rule). Returns the number of points removed.
  std::size_t slide(const Eigen::Vector3d& position);
  // Evicts the points seen least recently until at most max_points remain (down to 90 % of it, so
  // that eviction runs rarely). Returns the number removed.
  std::size_t enforce_budget();

  [[nodiscard]] std::size_t size() const { return points_.size() - free_.size(); }
  [[nodiscard]] VisualMapStats stats() const;

 private:
  struct Voxel {
    std::vector<std::uint32_t> ids;
    std::uint64_t visit = 0;
  };

  double voxel_size_;
  MapParams map_;
  std::size_t max_points_;
  std::unordered_map<VoxelKey, Voxel, VoxelKeyHash> voxels_;
  std::vector<VisualPoint> points_;
  std::vector<std::uint32_t> free_;
  std::uint64_t visit_ = 0;
  Eigen::Vector3d last_slide_position_ = Eigen::Vector3d::Zero();
  bool slid_once_ = false;
  std::uint64_t created_ = 0;
  std::uint64_t removed_sliding_ = 0;
  std::uint64_t removed_budget_ = 0;
};

}  // namespace livod::estimator::vio
