// Reads `estimator:` into estimator::EstimatorParams (defaults: FAST-LIVO2's avia.yaml).

#include "daemon/config/readers.hpp"

namespace livod::daemon::config_detail {

namespace {

void read_imu(MapReader& m, estimator::ImuParams& imu) {
  m.read("acc_cov", imu.acc_cov, left_open(0.0, 100.0));
  m.read("gyr_cov", imu.gyr_cov, left_open(0.0, 100.0));
  m.read("b_acc_cov", imu.b_acc_cov, left_open(0.0, 1.0));
  m.read("b_gyr_cov", imu.b_gyr_cov, left_open(0.0, 1.0));
  const bool samples = m.read("init_samples", imu.init_samples, 1, 100000);
  const bool time = m.read("init_time_s", imu.init_time_s, left_open(0.0, 60.0));
  if (samples && time) {
    m.problems().error(ProblemKind::inconsistent, m.child_path("init_time_s"),
                       m.key_at("init_time_s"),
                       "give either init_samples or init_time_s, not both");
  }
  {
    MapReader s = m.map("static_check");
    s.read("enabled", imu.static_check.enabled);
    s.read("max_acc_std_m_s2", imu.static_check.max_acc_std_m_s2, left_open(0.0, 10.0));
    s.read("max_gyro_std_rad_s", imu.static_check.max_gyro_std_rad_s, left_open(0.0, 1.0));
    s.finish();
  }
  m.read("init_gyro_bias", imu.init_gyro_bias);
  m.read("gravity_align", imu.gravity_align);
  m.read("gravity_est", imu.gravity_est);
  m.read("bias_est", imu.bias_est);
  m.read("gravity_m_s2", imu.gravity_m_s2, closed(9.7, 9.9));
  m.finish();
}

void read_lio(MapReader& m, estimator::LioParams& lio, std::set<std::string>& given) {
  ProblemList& problems = m.problems();
  const auto note = [&given](bool present, const char* key) {
    if (present) given.insert(std::string("lio.") + key);
  };
  m.read("max_iterations", lio.max_iterations, 1, 100);
  note(m.read("dept_err", lio.dept_err, left_open(0.0, 1.0)), "dept_err");
  note(m.read("beam_err_deg", lio.beam_err_deg, left_open(0.0, 5.0)), "beam_err_deg");
  m.read("incidence_term", lio.incidence_term);
  note(m.read("map_pose_covariance", lio.map_pose_covariance), "map_pose_covariance");
  m.read("max_incidence_deg", lio.max_incidence_deg, closed(0.0, 89.0));
  note(m.read("range_limit_m", lio.range_limit_m, closed(0.0, 10000.0)), "range_limit_m");
  note(m.read("dept_err_at_limit", lio.dept_err_at_limit, closed(0.0, 1.0)), "dept_err_at_limit");
  m.read("min_eigen_value", lio.min_eigen_value, left_open(0.0, 1.0));
  note(m.read("min_plane_spread_ratio", lio.min_plane_spread_ratio, closed(0.0, 100.0)),
       "min_plane_spread_ratio");
  note(m.read("map_min_move_m", lio.map_min_move_m, closed(0.0, 100.0)), "map_min_move_m");
  note(m.read("map_min_turn_deg", lio.map_min_turn_deg, left_open(0.0, 180.0)), "map_min_turn_deg");
  if (given.contains("lio.min_plane_spread_ratio") && given.contains("lio.map_pose_covariance") &&
      lio.min_plane_spread_ratio > 0.0 && lio.map_pose_covariance) {
    // The spread test compares a plane's points' spread with their covariances; the pose term
    // in them is common to a scan and spreads nothing, so every plane would fail it.
    problems.error(ProblemKind::inconsistent, m.child_path("min_plane_spread_ratio"),
                   m.key_at("min_plane_spread_ratio"),
                   "needs map_pose_covariance: false (it compares a plane's spread with its "
                   "points' noise, and the pose uncertainty in them is not noise)");
  }
  note(m.read("sigma_num", lio.sigma_num, left_open(0.0, 10.0)), "sigma_num");
  m.read("voxel_size", lio.voxel_size, closed(0.05, 10.0));
  m.read("max_layer", lio.max_layer, 0, 4);
  note(m.read("max_points_num", lio.max_points_num, 5, 10000), "max_points_num");
  m.read("max_cov_points", lio.max_cov_points, 5, 10000);
  if (const auto v = m.take("layer_init_num"); v && !v->node.IsNull()) {
    // A plane fit needs at least 3 points.
    const auto numbers = parse_numbers(problems, *v, 1, 8, closed(3.0, 1000.0));
    if (numbers) {
      std::vector<int> layers;
      bool integral = true;
      for (double n : *numbers) {
        integral = integral && n == static_cast<double>(static_cast<int>(n));
        layers.push_back(static_cast<int>(n));
      }
      if (!integral) {
        problems.error(ProblemKind::wrong_type, v->path, v->at, "expected whole numbers");
      } else if (layers.size() < static_cast<std::size_t>(lio.max_layer) + 1) {
        problems.error(ProblemKind::inconsistent, v->path, v->at,
                       "has " + std::to_string(layers.size()) + " entries but max_layer " +
                           std::to_string(lio.max_layer) + " needs " +
                           std::to_string(lio.max_layer + 1) + " (one per layer)");
      } else {
        lio.layer_init_num = layers;
      }
    }
  }
  m.read("plane_update_points", lio.plane_update_points, 1, 1000);
  note(m.read("point_filter_num", lio.point_filter_num, 1, 1000), "point_filter_num");
  note(m.read("point_budget", lio.point_budget, 0, 1000000), "point_budget");
  m.read("blind", lio.blind, closed(0.0, 100.0));
  const bool filter_size = m.read("filter_size_surf", lio.filter_size_surf, closed(0.0, 10.0));
  note(filter_size, "filter_size_surf");
  if (filter_size && lio.filter_size_surf >= lio.voxel_size) {
    problems.warning(ProblemKind::inconsistent, m.child_path("filter_size_surf"),
                     m.key_at("filter_size_surf"),
                     "is not smaller than voxel_size: voxels get too few points to fit planes");
  }
  {
    MapReader c = m.map("convergence");
    c.read("rotation_deg", lio.convergence.rotation_deg, left_open(0.0, 1.0));
    c.read("translation_m", lio.convergence.translation_m, left_open(0.0, 0.1));
    c.finish();
  }
  m.finish();
}

void read_map(MapReader& m, estimator::MapParams& map) {
  m.read("sliding", map.sliding);
  m.read("half_extent_m", map.half_extent_m, closed(1.0, 10000.0));
  m.read("slide_threshold_m", map.slide_threshold_m, left_open(0.0, 10000.0));
  int max_voxels = static_cast<int>(map.max_voxels);
  if (m.read("max_voxels", max_voxels, 1000, 100000000)) {
    map.max_voxels = static_cast<std::size_t>(max_voxels);
  }
  if (map.slide_threshold_m >= map.half_extent_m) {
    m.problems().error(ProblemKind::inconsistent, m.child_path("slide_threshold_m"),
                       m.key_at("slide_threshold_m"),
                       "must be smaller than half_extent_m (" + format_number(map.half_extent_m) +
                           "), or the robot leaves the map before it slides");
  }
  m.finish();
}

void read_vio(MapReader& m, estimator::VioParams& vio) {
  ProblemList& problems = m.problems();
  m.read("enabled", vio.enabled);
  m.read("max_iterations", vio.max_iterations, 1, 100);
  m.read("outlier_threshold", vio.outlier_threshold, left_open(0.0, 1e6));
  m.read("img_point_cov", vio.img_point_cov, left_open(0.0, 1e6));
  if (m.read("patch_size", vio.patch_size, 4, 16) && vio.patch_size % 2 != 0) {
    problems.error(ProblemKind::invalid_value, m.child_path("patch_size"), m.key_at("patch_size"),
                   "must be even (patches are centred between pixels)");
  }
  m.read("pyramid_levels", vio.pyramid_levels, 1, 6);
  m.read("normal_en", vio.normal_en);
  m.read("exposure_estimate", vio.exposure_estimate);
  m.read("inv_expo_cov", vio.inv_expo_cov, left_open(0.0, 10.0));
  m.read("grid_cell_px", vio.grid_cell_px, 4, 1000);
  m.read("huber_k", vio.huber_k, closed(0.0, 100.0));
  m.read("min_patches", vio.min_patches, 1, 10000);
  m.read("max_view_angle_deg", vio.max_view_angle_deg, left_open(0.0, 90.0));
  m.read("min_corner_score", vio.min_corner_score, closed(0.0, 1e6));
  m.read("max_visual_points", vio.max_visual_points, 100, 10000000);
  m.read("max_observations", vio.max_observations, 2, 100);
  m.read("observation_distance_m", vio.observation_distance_m, left_open(0.0, 100.0));
  m.read("observation_angle_deg", vio.observation_angle_deg, left_open(0.0, 180.0));
  m.read("observation_pixels", vio.observation_pixels, left_open(0.0, 10000.0));
  m.read("visual_voxel_size", vio.visual_voxel_size, closed(0.05, 10.0));
  m.read("depth_discontinuity_m", vio.depth_discontinuity_m, left_open(0.0, 100.0));
  m.read("image_timeout_s", vio.image_timeout_s, left_open(0.0, 10.0));
  {
    MapReader c = m.map("convergence");
    c.read("rotation_deg", vio.convergence.rotation_deg, left_open(0.0, 1.0));
    c.read("translation_m", vio.convergence.translation_m, left_open(0.0, 0.1));
    c.finish();
  }
  m.finish();
}

}  // namespace

void read_estimator(MapReader& reader, estimator::EstimatorParams& params,
                    std::set<std::string>& given) {
  reader.read("threads", params.threads, 0, 256);
  {
    MapReader m = reader.map("imu");
    read_imu(m, params.imu);
  }
  {
    MapReader m = reader.map("lio");
    read_lio(m, params.lio, given);
  }
  {
    MapReader m = reader.map("map");
    read_map(m, params.map);
  }
  {
    MapReader m = reader.map("vio");
    read_vio(m, params.vio);
  }
  reader.finish();
}

}  // namespace livod::daemon::config_detail
