#pragma once
// The visual half of LIVO (fast-livo2-notes.md 1.4): one image at the time of the LIO update
// just made, through these steps -
//
//   pyramid    grey (and resized by the camera's scale), real pyramid (image_pyramid.hpp)
//   selection  the current scan's points give a sparse depth image and the visual voxels to
//              look in; the closest visual point per grid cell, in view, not next to a LiDAR
//              depth jump (occlusion, edges), not seen too obliquely; its reference patch warped
//              by the plane-induced homography (warp.hpp) for every level; a photometric gate
//              with the exposure change estimated robustly first
//   update     coarse to fine over the levels, iterated ESIKF steps on the shared 19-D state
//              (rotation, position, inverse exposure) with Huber-weighted photometric rows
//              (photometric.hpp); a level stops when a step does not lower the error; the
//              covariance is updated once, from the last linearisation
//   map        new reference patches for points seen from far enough elsewhere, reference
//              refresh (NCC with the other patches + viewing angle, FAST-LIVO2's score), normals
//              from the LiDAR map's planes, new points from LiDAR points with planes in the grid
//              cells left empty (highest Shi-Tomasi score), sliding and budget
//
// The processor never sees a file or a thread; it keeps no image beyond the current one.

#include <Eigen/Geometry>
#include <cstdint>
#include <functional>
#include <vector>

#include "core/camera_model.hpp"
#include "core/image.hpp"
#include "estimator/filter/state.hpp"
#include "estimator/map/voxel_map.hpp"
#include "estimator/params.hpp"
#include "estimator/task_runner.hpp"
#include "estimator/vio/camera_projection.hpp"
#include "estimator/vio/image_pyramid.hpp"
#include "estimator/vio/photometric.hpp"
#include "estimator/vio/visual_map.hpp"

namespace livod::estimator::vio {

// The camera the estimator uses: its model at full resolution, the scale images are resized by
// (FAST-LIVO2 `scale`) and its pose in the body (IMU) frame.
struct VioCamera {
  CameraIntrinsics intrinsics;  // full resolution
  double scale = 1.0;
  Eigen::Isometry3d T_imu_cam = Eigen::Isometry3d::Identity();
};

struct VioTimings {
  double pyramid_ms = 0.0;    // grey conversion, resize, pyramid
  double selection_ms = 0.0;  // depth image, retrieval, grid, warps, gate
  double update_ms = 0.0;     // the coarse-to-fine iterated update
  double map_ms = 0.0;        // observations, reference refresh, new points, sliding, budget
  double total_ms = 0.0;
  // The same in CPU time of the calling thread: unlike wall time it does not count time the
  // thread spent preempted (the figures to compare on a loaded machine).
  double pyramid_cpu_ms = 0.0;
  double selection_cpu_ms = 0.0;
  double update_cpu_ms = 0.0;
  double map_cpu_ms = 0.0;
  double cpu_ms = 0.0;
  // CPU time of the whole process over the image (the calling thread and the TaskRunner's workers
  // together: the work the update costs; includes any other thread of the process that ran then).
  double process_cpu_ms = 0.0;
};

// One drawn patch for --debug-images.
struct VioPatchDebug {
  enum class Status : std::uint8_t { tracked, rejected, created };
  Eigen::Vector2f pixel = Eigen::Vector2f::Zero();  // level 0 of the resized image
  Status status = Status::tracked;
  float rms_before = 0.0F;  // photometric RMS at level 0 before the update (grey levels)
  float rms_after = 0.0F;
};

struct VioReport {
  bool ran = false;      // the image was processed (false: wrong size or format, see `problem`)
  bool updated = false;  // the state was corrected (enough patches)
  const char* problem = "";
  int candidates = 0;        // visual points in the scan's voxels, in view
  int selected = 0;          // one per grid cell, after the depth and angle checks
  int rejected_outlier = 0;  // failed the photometric gate
  int patches = 0;           // used by the update
  int iterations = 0;        // steps over all levels
  int new_points = 0;
  int new_observations = 0;
  double rms_before = 0.0;  // photometric RMS of the used patches at level 0 (grey levels)
  double rms_after = 0.0;
  double inv_exposure = 1.0;  // tau after the update
  VisualMapStats map;         // refreshed every 10th image
  VioTimings timings;
  std::vector<VioPatchDebug> debug;  // filled when asked
};

class VioProcessor {
 public:
  // `runner` (optional, must outlive the processor) spreads the per-point and per-patch work over
  // the worker pool; the results do not depend on it.
  VioProcessor(const VioParams& params, const MapParams& map, const VioCamera& camera,
               TaskRunner* runner = nullptr);

  // Processes one image taken at the belief's time (the pipeline has just propagated and run the
  // LIO update to it). scan_world / scan_normals: the scan's points in the world after that
  // update (positions `p`; read where they are, the scan is not copied) and the normals of the
  // planes they matched (zero: none). Updates `belief`.
  VioReport process(const ImageFrame& frame, Belief& belief,
                    const std::vector<CovPoint>& scan_world,
                    const std::vector<Eigen::Vector3d>& scan_normals, const VoxelMap& lidar_map,
                    bool debug);

  // The colour of world points in the last image processed, seen from state x: 0x00RRGGBB, and
  // `seen` 1 where the point projects into the image (grey images give grey colours).
  void colorize(const State& x, const std::vector<Eigen::Vector3d>& p_world,
                std::vector<std::uint32_t>& rgb, std::vector<std::uint8_t>& seen) const;

  [[nodiscard]] const VisualMap& map() const { return map_; }
  // The last image as the update saw it (grey, resized), for debug drawing.
  [[nodiscard]] const cv::Mat& last_grey() const { return grey_; }
  [[nodiscard]] const CameraModel& camera() const { return camera_; }

 private:
  struct Patch;
  bool prepare_image(const ImageFrame& frame, VioReport& report);
  // Projects the scan (at the prior pose) once: pixels, ranges, visual voxel keys, depth image.
  void project_scan(const State& x, const std::vector<CovPoint>& scan_world);
  void for_range(std::size_t n, std::size_t grain,
                 const std::function<void(std::size_t, std::size_t)>& fn) const;
  [[nodiscard]] bool near_depth_jump(const Eigen::Vector2d& px, double depth) const;
  void select(const State& x, VioReport& report);
  // Fills `out` (levels x P^2) with the reference patch warped into the current view.
  bool warp_reference(const State& x, Patch& patch, float* out) const;
  double gate(const State& x, VioReport& report);
  void update(Belief& belief, double tau_start, VioReport& report);
  void maintain(const State& x, const std::vector<CovPoint>& scan_world,
                const std::vector<Eigen::Vector3d>& scan_normals, const VoxelMap& lidar_map,
                VioReport& report);
  bool capture(const State& x, const Eigen::Vector2d& px, PatchObservation& obs) const;
  // Adds a reference patch, keeps at most max_observations and picks the reference (FAST-LIVO2's
  // score). `work`: scratch space (unit patches).
  void add_observation(VisualPoint& point, PatchObservation obs, std::vector<float>& work) const;
  // The level-0 patch of an observation, zero-mean and unit-norm (P^2 values).
  void unit_patch(const PatchObservation& obs, float* out) const;
  void refine_normal(VisualPoint& point, const Eigen::Vector3d& camera_center,
                     const VoxelMap& lidar_map) const;

  VioParams params_;
  TaskRunner* runner_ = nullptr;
  CameraIntrinsics full_;
  CameraModel camera_;  // at the processing scale
  CameraExtrinsic extrinsic_;
  VisualMap map_;
  ImagePyramid pyramid_;
  cv::Mat grey_;
  cv::Mat colour_;  // the frame as given (BGR or grey), for colorize()
  double colour_scale_ = 1.0;
  std::uint64_t frame_ = 0;
  int grid_cols_ = 0;
  int grid_rows_ = 0;
  // Sparse LiDAR depth image at 1/kDepthCell resolution (min depth per cell, +inf: none).
  static constexpr int kDepthCell = 4;
  int depth_cols_ = 0;
  int depth_rows_ = 0;
  std::vector<float> depth_;
  // Per-image work arrays (kept: no allocation in steady state).
  std::vector<std::uint32_t> candidates_;
  std::vector<std::int32_t> cell_point_;  // per grid cell: index into patches_, -1: none
  std::vector<float> cell_depth_;
  struct Patch {
    std::uint32_t id = 0;                               // visual point
    Eigen::Vector3d p_world = Eigen::Vector3d::Zero();  // its position (no map lookup per step)
    Eigen::Vector2d px = Eigen::Vector2d::Zero();
    double depth = 0.0;
    int cell = 0;
    std::uint32_t level_mask = 0;  // levels whose reference warp is valid
    std::size_t ref_offset = 0;    // into refs_: levels x P^2 values (tau_ref applied)
    bool used = false;             // passed the gate
    float rms_before = 0.0F;
    Eigen::Vector2d px_after = Eigen::Vector2d::Zero();  // pixel at the updated state
    double mse_after = -1.0;  // photometric mean squared error there (< 0: not evaluated)
  };
  std::vector<Patch> patches_;
  std::vector<float> refs_;
  std::vector<double> ratios_;
  std::vector<std::uint8_t> occupied_;
  std::vector<std::uint8_t> cell_tried_;
  std::vector<std::uint32_t> cell_count_;
  std::vector<std::uint32_t> cell_seen_;
  struct ScoredPoint {
    std::uint32_t point = 0;  // index into the scan
    std::uint32_t cell = 0;
    float score = 0.0F;  // Shi-Tomasi
  };
  std::vector<ScoredPoint> scored_;        // new-point candidates of the image
  std::vector<std::int64_t> scan_cell_;    // per scan point: its empty grid cell, -1: none
  std::vector<Eigen::Vector2f> scan_px_;   // the scan's pixels at the prior pose
  std::vector<float> scan_range_;          // their ranges from the camera; < 0: not in the image
  std::vector<VoxelKey> scan_keys_;        // the visual voxels of those in the image
  std::vector<VoxelKey> scan_point_keys_;  // per scan point (set where the range is >= 0)
  std::vector<PatchNormals> block_sums_;
  std::vector<PatchEval> gate_evals_;
  std::vector<double> gate_ratios_;     // per patch, NaN: none
  std::vector<std::uint32_t> observe_;  // patches that get a new reference patch
  std::vector<std::uint8_t> observed_;  // per entry of observe_: it did (the capture fit)
  double cos_half_fov_ = -1.0;  // cosine of the widest ray's angle off axis (+ margin); -1: none
  VisualMapStats map_stats_;
  bool debug_ = false;
};

}  // namespace livod::estimator::vio
