#pragma once
// Estimator parameters: plain structs with in-class defaults. Names follow FAST-LIVO2 where that
// system has the parameter; defaults are its shipped avia.yaml (the hand-held Livox Avia rig), see
// docs/configuration.md for every value, its unit and its origin. Constants that FAST-LIVO2
// hard-codes (plane refit size, visual voxel size, observation limits, ...) are parameters here.
//
// This header must not depend on the configuration loader or on YAML: the daemon fills these
// structs from the config file, tests and benchmarks fill them in code.

#include <optional>
#include <vector>

namespace livod::estimator {

// Motion check during IMU initialisation (FAST-LIVO2 has none and silently assumes a static
// start). The initialisation window restarts while the platform moves.
struct StaticCheckParams {
  bool enabled = true;
  double max_acc_std_m_s2 = 0.2;     // std of |accel| over the window
  double max_gyro_std_rad_s = 0.05;  // std of each gyro axis over the window
};

struct ImuParams {
  // Continuous-time process noise scales of the propagation (FAST-LIVO2 acc_cov, gyr_cov).
  double acc_cov = 0.5;  // (m/s^2)^2
  double gyr_cov = 0.3;  // (rad/s)^2
  // Bias random walks. FAST-LIVO2 hard-codes 1e-4 and ignores these keys; here they are used.
  double b_acc_cov = 1e-4;
  double b_gyr_cov = 1e-4;
  // Initialisation window: a number of IMU samples (FAST-LIVO2 imu_int_frame), or, when
  // init_time_s > 0, a duration (independent of the IMU rate).
  int init_samples = 30;
  double init_time_s = 0.0;
  StaticCheckParams static_check;
  // Start the gyro bias at the mean gyro of the (static) init window instead of zero.
  bool init_gyro_bias = true;
  bool gravity_align = false;  // rotate the world so that gravity is -z at start
  bool gravity_est = true;     // estimate gravity in the filter (FAST-LIVO2 gravity_est_en)
  bool bias_est = true;        // estimate b_g and b_a (FAST-LIVO2 ba_bg_est_en)
  double gravity_m_s2 = 9.81;  // magnitude the initial gravity is scaled to
};

// Iteration stops when one update step moves the state less than this.
struct ConvergenceParams {
  double rotation_deg = 0.01;
  double translation_m = 0.00015;
};

struct LioParams {
  int max_iterations = 5;
  double dept_err = 0.02;      // range noise sigma (m)
  double beam_err_deg = 0.05;  // bearing noise sigma (deg)
  // The incidence-angle term of the point covariance (the hit smears along the ray by
  // r tan(incidence) beam_err): in association and in the plane fits. FAST-LIVO2 leaves it out.
  bool incidence_term = true;
  double max_incidence_deg = 80.0;  // grazing hits are modelled as at this incidence
  // The range noise grows as the echo weakens (map/point_covariance.hpp): the detection limit of
  // a typical target seen head-on (m; 0: the range noise is dept_err at any range) and the range
  // noise sigma at the limit (m). Off by default (docs/estimator.md, "Known limits").
  // Add the pose uncertainty at insertion to the map points' covariances (FAST-LIVO2, VoxelMap).
  // The pose error is common to the whole scan, not independent per point: off, a street drive's
  // pitch bias fell from -1.43 to -0.14 mrad, but sparse-ring streets lose track (estimator.md
  // "Long drives"). On here (FAST-LIVO2); the daemon chooses per model (estimator_defaults.hpp).
  bool map_pose_covariance = true;
  double range_limit_m = 0.0;
  double dept_err_at_limit = 0.0;
  double min_eigen_value = 0.0025;  // planarity: smallest eigenvalue (m^2) below this
  // A plane must also span two directions: its points' spread along the narrower one (the middle
  // eigenvalue) at least this many times their noise variance along it, or they are a line, such
  // as one ring's hits, that the noise along the rays makes look flat (map/plane.hpp). A line is
  // not matched and not split; it becomes a plane when more points span it. 0: off (FAST-LIVO2).
  // Compared with the map points' covariances: meant for lio.map_pose_covariance off, as the pose
  // term does not spread the points.
  double min_plane_spread_ratio = 0.0;
  double sigma_num = 3.0;   // association gate, in sigmas
  double voxel_size = 0.5;  // root voxel edge (m)
  int max_layer = 2;        // octree depth below the root voxel
  int max_points_num = 50;  // a plane freezes after this many points
  // A plane node stores at most this many points (their covariances give the plane's). Past them,
  // while max_points_num is larger, the plane is refitted from the moments of all its points with
  // that covariance scaled down (VoxelMap's max_cov_points_size): more points per plane at the
  // memory of a frozen node.
  int max_cov_points = 50;
  // A scan goes into the map only from a new viewpoint (map/insert_gate.hpp): once the IMU moved
  // at least map_min_move_m or turned at least map_min_turn_deg since the last inserted scan.
  // 0: every scan (FAST-LIVO2). One LiDAR only (its groups are whole scans).
  double map_min_move_m = 0.0;
  double map_min_turn_deg = 10.0;
  std::vector<int> layer_init_num = {5, 5, 5, 5, 5};  // points to fit a plane, per layer
  int plane_update_points = 5;    // new points that trigger a plane refit (hard-coded upstream)
  int point_filter_num = 1;       // keep one point in n (lio/point_filter.hpp)
  double blind = 0.8;             // minimum range (m)
  double filter_size_surf = 0.1;  // scan voxel-grid downsampling (m); 0 disables
  // > 0: points per scan after downsampling. The cell grows above filter_size_surf (up to
  // voxel_size) whenever a scan brings more (lio/point_budget.hpp): a fixed per-frame cost for
  // any sensor and place. 0: the cell is filter_size_surf. The daemon sets it per sensor model
  // (daemon/config/estimator_defaults.hpp).
  int point_budget = 0;
  ConvergenceParams convergence;
};

// One LiDAR's own point settings where several LiDARs feed the estimator (docs/estimator.md
// "Several LiDARs"): an unset value is LioParams' (the estimator-wide one).
struct LidarLioParams {
  std::optional<double> dept_err;       // range noise sigma (m) of this LiDAR's points
  std::optional<double> beam_err_deg;   // bearing noise sigma (deg) of this LiDAR's points
  std::optional<int> point_filter_num;  // one point in n of this LiDAR's (lio/point_filter.hpp)
  // Association gate of this LiDAR's rows in sigmas (LioParams::sigma_num otherwise).
  std::optional<double> sigma_num;
  // Its points are inserted into the map. false: they are matched against the planes the other
  // LiDARs build, and build none (a sparse spinning LiDAR cuts a voxel in single-ring lines,
  // which pass the planarity test as planes whose tilt about the line is unobserved).
  bool build_map = true;
};

// The voxel map slides with the robot so that memory stays bounded.
struct MapParams {
  bool sliding = true;
  double half_extent_m = 50.0;     // voxels farther than this from the robot (per axis) go
  double slide_threshold_m = 8.0;  // re-centre after moving this far
  // A hard budget of root voxels: over it, the voxels farthest from the robot go (down to 90 %),
  // sliding or not. The box alone does not bound memory: a diverging estimate fills its volume
  // with scans in every orientation (a simulated room grew by 1 GB/min). About 1.7 KB per voxel
  // on a street (docs/estimator.md): the default is ~0.5 GB, ten times a street drive's map.
  std::size_t max_voxels = 300000;
};

struct VioParams {
  bool enabled = true;                // use cameras when the configuration has one
  int max_iterations = 5;             // per pyramid level
  double outlier_threshold = 1000.0;  // per-pixel mean squared photometric error gate
  double img_point_cov = 100.0;       // photometric noise variance (grey levels^2)
  // Huber kernel on every pixel's residual at huber_k * sqrt(img_point_cov) grey levels
  // (FAST-LIVO2 has no robust kernel, defect 11).
  double huber_k = 1.345;
  int patch_size = 8;      // patch edge (px)
  int pyramid_levels = 3;  // image pyramid levels used by the update
  bool normal_en = true;   // warp patches by the plane-induced homography
  bool exposure_estimate = true;
  double inv_expo_cov = 0.1;  // inverse-exposure random walk
  int grid_cell_px = 30;      // one visual point per grid cell (cell edge in px)
  int min_patches = 10;       // fewer usable patches in an image: no visual update
  // Points seen more obliquely than this (angle between the view ray and the surface normal) are
  // not used (the paper's rejection; FAST-LIVO2's code has it commented out).
  double max_view_angle_deg = 80.0;
  // New visual points need a Shi-Tomasi score (smallest eigenvalue of the 8x8 structure tensor,
  // mean per pixel, grey levels^2 / px^2) of at least this: flat patches constrain nothing.
  double min_corner_score = 4.0;
  int max_visual_points = 20000;  // the visual map is bounded (FAST-LIVO2's grows forever)
  // Reference patches kept per visual point (FAST-LIVO2 keeps up to 30 observations and a
  // reference to each whole image; here each is a small patch per pyramid level).
  int max_observations = 8;
  // A point gets a new observation when the camera moved this far, turned this much or the point
  // moved this many pixels since its last one (FAST-LIVO2 hard-codes 0.5 m, 0.3 rad, 40 px).
  double observation_distance_m = 0.5;
  double observation_angle_deg = 17.2;
  double observation_pixels = 40.0;
  double visual_voxel_size = 0.5;      // visual map voxel edge (m), hard-coded upstream
  double depth_discontinuity_m = 0.5;  // reject points near a LiDAR depth jump
  // LIO runs alone, at LiDAR rate, for a scan when no image arrives within this time (and within
  // a scan period) after its end: the longest LIO waits for a camera (sync/measurement_sync.hpp).
  double image_timeout_s = 0.15;
  // A level stops iterating when one step moves the state less than this (hard-coded upstream).
  ConvergenceParams convergence{0.001, 0.00001};
};

struct EstimatorParams {
  // Threads for residual rows and map refits (FAST-LIVO2 uses up to 4 OpenMP threads); 0: one per
  // core. The trajectory does not depend on it.
  int threads = 0;
  ImuParams imu;
  LioParams lio;
  MapParams map;
  VioParams vio;
};

}  // namespace livod::estimator
