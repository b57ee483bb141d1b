#include "estimator/pipeline.hpp"

#include <algorithm>
#include <chrono>
#include <stdexcept>
#include <string>

#include "core/so3.hpp"
#include "core/units.hpp"
#include "estimator/imu/propagation.hpp"
#include "estimator/lio/point_filter.hpp"

namespace livod::estimator {
namespace {

double ms_since(std::chrono::steady_clock::time_point t0) {
  return std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count();
}

IterationParams iteration_params(const LioParams& lio) {
  IterationParams p;
  p.max_iterations = lio.max_iterations;
  p.converged_rotation_rad = lio.convergence.rotation_deg * M_PI / 180.0;
  p.converged_translation_m = lio.convergence.translation_m;
  return p;
}

PointNoise point_noise(const LioParams& lio, const LidarLioParams& own = {}) {
  PointNoise n;
  n.range_sigma_m = own.dept_err.value_or(lio.dept_err);
  n.bearing_sigma_rad = own.beam_err_deg.value_or(lio.beam_err_deg) * M_PI / 180.0;
  n.max_incidence_rad = lio.max_incidence_deg * M_PI / 180.0;
  n.range_limit_m = lio.range_limit_m;
  n.sigma_at_limit_m = lio.dept_err_at_limit;
  return n;
}

std::vector<Eigen::Isometry3d> all_lidars(const PipelineOptions& o) {
  std::vector<Eigen::Isometry3d> all{o.T_imu_lidar};
  all.insert(all.end(), o.T_imu_more_lidars.begin(), o.T_imu_more_lidars.end());
  return all;
}

}  // namespace

LioPipeline::LioPipeline(PipelineOptions options)
    : options_(std::move(options)),
      T_imu_lidars_(all_lidars(options_)),
      initializer_(options_.params.imu),
      sync_(SyncParams{options_.max_queued_scans, options_.max_queued_imu, 8,
                       options_.params.vio.image_timeout_s, T_imu_lidars_.size(),
                       options_.lidar_wait_s}),
      map_(std::make_unique<VoxelMap>(options_.params.lio, options_.params.map)),
      downsampler_(options_.params.lio.filter_size_surf),
      map_gates_(T_imu_lidars_.size(),
                 MapInsertGate(options_.params.lio.map_min_move_m,
                               options_.params.lio.map_min_turn_deg * kDegToRad)) {
  if (T_imu_lidars_.size() > kMaxLidars) {
    throw std::invalid_argument("LioPipeline: at most " + std::to_string(kMaxLidars) + " LiDARs");
  }
  if (T_imu_lidars_.size() > 1 && options_.camera && options_.params.vio.enabled) {
    throw std::invalid_argument(
        "LioPipeline: the visual update runs with one LiDAR only (several LiDARs: LIO)");
  }
  if (options_.lidar_lio.size() > T_imu_lidars_.size()) {
    throw std::invalid_argument("LioPipeline: more per-LiDAR settings than LiDARs");
  }
  options_.lidar_lio.resize(T_imu_lidars_.size());
  if (std::none_of(options_.lidar_lio.begin(), options_.lidar_lio.end(),
                   [](const LidarLioParams& l) { return l.build_map; })) {
    throw std::invalid_argument("LioPipeline: no LiDAR builds the map");
  }
  const LioParams& lio = options_.params.lio;
  if (lio.point_budget > 0 && lio.filter_size_surf > 0.0) {
    point_budget_.emplace(lio.point_budget, lio.filter_size_surf,
                          std::max(lio.filter_size_surf, lio.voxel_size));
  }
  p2p_ = std::make_unique<PointToPlane>(*map_, T_imu_lidars_, options_.runner,
                                        point_noise(options_.params.lio),
                                        options_.params.lio.incidence_term);
  for (std::size_t l = 0; l < T_imu_lidars_.size(); ++l) {
    noise_[l] = point_noise(options_.params.lio, options_.lidar_lio[l]);
    p2p_->set_lidar_noise(l, noise_[l]);
    if (options_.lidar_lio[l].sigma_num) p2p_->set_lidar_gate(l, *options_.lidar_lio[l].sigma_num);
  }
  if (options_.camera && options_.params.vio.enabled) {
    vio_ = std::make_unique<vio::VioProcessor>(options_.params.vio, options_.params.map,
                                               *options_.camera, options_.runner);
    sync_.enable_images(true);
  }
}

LioPipeline::~LioPipeline() = default;

void LioPipeline::for_points(std::size_t n,
                             const std::function<void(std::size_t, std::size_t)>& fn) const {
  if (options_.runner != nullptr) {
    parallel_for(*options_.runner, n, 1024, fn);
  } else {
    fn(0, n);
  }
}

void LioPipeline::add_imu(const ImuSample& sample) {
  if (initializer_.done()) {
    sync_.add_imu(sample);
    return;
  }
  ++init_counters_.imu_in;
  if (have_prev_imu_ && sample.stamp.mapped <= prev_imu_.stamp.mapped) {
    ++init_counters_.imu_out_of_order;
    return;
  }
  prev_imu_ = sample;
  have_prev_imu_ = true;
  // The initialisation ends at this sample or a later one: scans ending by now precede it.
  while (!early_scans_.empty() &&
         MeasurementSync::scan_end(early_scans_.front().scan) <= sample.stamp.mapped) {
    early_scans_.pop_front();
    ++counters_.scans_before_init;
  }
  if (initializer_.add(sample)) {
    belief_ = *initializer_.result();
    state_time_ = initializer_.time();
    sync_.start(state_time_);
    init_time_ = state_time_;
    // The scans that begin after the initialisation are the filter's first, whichever arrived
    // first: replay (time order) and live (arrival order) start from the same scan.
    for (EarlyScan& early : early_scans_) {
      if (early.scan.start.mapped < init_time_) {
        ++counters_.scans_before_init;
        continue;
      }
      --init_counters_.scans_in;  // the sync counts it again
      sync_.add_scan(std::move(early.scan), early.lidar);
    }
    early_scans_.clear();
  }
}

void LioPipeline::add_scan(LidarScan scan, std::size_t lidar) {
  if (lidar >= T_imu_lidars_.size()) return;
  if (!scan.empty()) scan_periods_[lidar] = Nanoseconds(scan.span_ns());
  if (initializer_.done()) {
    // A scan that began before the initialisation ended has points the filter holds no state
    // for: dropped whichever way it arrived, so live and replay start from the same scan.
    if (!scan.empty() && scan.start.mapped < init_time_) {
      ++init_counters_.scans_in;
      ++counters_.scans_before_init;
      return;
    }
    sync_.add_scan(std::move(scan), lidar);
    return;
  }
  ++init_counters_.scans_in;
  if (scan.empty()) return;
  if (have_prev_imu_ && MeasurementSync::scan_end(scan) <= prev_imu_.stamp.mapped) {
    ++counters_.scans_before_init;
    return;
  }
  early_scans_.push_back(EarlyScan{std::move(scan), lidar});
  if (early_scans_.size() > options_.max_queued_scans) {
    early_scans_.pop_front();
    ++counters_.scans_before_init;
  }
}

void LioPipeline::add_image(ImageFrame image) {
  if (!vio_) {
    ++images_unused_;
    return;
  }
  // Before the IMU initialisation there is no timeline yet: the sync drops nothing it cannot use
  // later, and an image before the start would be late anyway.
  if (!initializer_.done()) {
    ++images_unused_;
    return;
  }
  sync_.add_image(std::move(image));
}

PipelineCounters LioPipeline::counters() const {
  PipelineCounters c = counters_;
  const SyncCounters& s = sync_.counters();
  c.images_in = s.images_in + images_unused_;
  c.images_unused = images_unused_ + s.images_before_map;
  c.images_late = s.images_late;
  c.images_dropped = s.images_out_of_order + s.images_queue_overflow;
  c.images_rejected = images_rejected_;
  c.image_groups = s.image_groups;
  c.vio_updates = vio_updates_;
  c.scans_in = init_counters_.scans_in + s.scans_in;
  c.scans_out_of_order = s.scans_out_of_order;
  c.scans_queue_overflow = s.scans_queue_overflow;
  c.scans_late = s.scans_late;
  c.points_late = s.points_late;
  c.imu_in = init_counters_.imu_in + s.imu_in;
  c.imu_out_of_order = init_counters_.imu_out_of_order + s.imu_out_of_order;
  c.imu_queue_overflow = s.imu_queue_overflow;
  return c;
}

std::size_t LioPipeline::process(const std::function<void(const PipelineOutput&)>& on_output,
                                 std::size_t max_groups) {
  std::size_t done = 0;
  while (done < max_groups && take_group()) {
    process_taken(on_output, {});
    ++done;
  }
  return done;
}

bool LioPipeline::take_group() {
  return sync_.next(group_);
}

void LioPipeline::process_taken(const std::function<void(const PipelineOutput&)>& on_output,
                                const EstimateCallback& on_estimate) {
  process_group(group_, on_output, on_estimate);
}

void LioPipeline::propagate_to(const MeasurementGroup& group, ImuPoseTrack& track) {
  const auto& ip = options_.params.imu;
  const double inv_expo_cov = options_.params.vio.inv_expo_cov;
  const MappedTime t_end = group.t_update;
  track.clear();
  auto push_pose = [&](const ImuReading& m) {
    ImuPose pose;
    pose.t = state_time_;
    pose.R_world_imu = belief_.x.R_world_imu;
    pose.p_world_imu = belief_.x.p_world_imu;
    pose.v_world = belief_.x.v_world;
    pose.omega_imu = m.gyro_rad_s - belief_.x.bias_gyro;
    pose.acc_world =
        belief_.x.R_world_imu * (m.accel_m_s2 - belief_.x.bias_accel) + belief_.x.gravity_world;
    track.push(pose);
  };
  for (const ImuSample& s : group.imu) {
    const double dt = to_seconds(s.stamp.mapped - state_time_);
    if (dt <= 0.0) {
      prev_imu_ = s;
      continue;
    }
    // Mean of the linearly interpolated signal over [state_time_, s]: after an interval cut at
    // the previous update time, the step starts between prev_imu_ and s, not at prev_imu_.
    const double span = to_seconds(s.stamp.mapped - prev_imu_.stamp.mapped);
    const double a0 =
        span > 0.0 ? std::max(0.0, to_seconds(state_time_ - prev_imu_.stamp.mapped) / span) : 0.0;
    const Eigen::Vector3d g_start =
        prev_imu_.gyro_rad_s + a0 * (s.gyro_rad_s - prev_imu_.gyro_rad_s);
    const Eigen::Vector3d a_start =
        prev_imu_.accel_m_s2 + a0 * (s.accel_m_s2 - prev_imu_.accel_m_s2);
    const ImuReading m{0.5 * (g_start + s.gyro_rad_s), 0.5 * (a_start + s.accel_m_s2)};
    push_pose(m);
    propagate(belief_, m, dt, ip, inv_expo_cov);
    state_time_ = s.stamp.mapped;
    prev_imu_ = s;
  }
  // The last interval is cut at the update time, interpolating the next sample to that time.
  const double dt = to_seconds(t_end - state_time_);
  if (dt > 0.0) {
    ImuReading m{prev_imu_.gyro_rad_s, prev_imu_.accel_m_s2};
    if (group.imu_after) {
      const ImuSample& next = *group.imu_after;
      const double span = to_seconds(next.stamp.mapped - prev_imu_.stamp.mapped);
      const double a = span > 0.0 ? to_seconds(t_end - prev_imu_.stamp.mapped) / span : 0.0;
      const Eigen::Vector3d g_end =
          prev_imu_.gyro_rad_s + a * (next.gyro_rad_s - prev_imu_.gyro_rad_s);
      const Eigen::Vector3d a_end =
          prev_imu_.accel_m_s2 + a * (next.accel_m_s2 - prev_imu_.accel_m_s2);
      // Mean over [state_time_, t_end] of the linear interpolation between the two samples.
      const double a0 = span > 0.0 ? to_seconds(state_time_ - prev_imu_.stamp.mapped) / span : 0.0;
      const Eigen::Vector3d g_start =
          prev_imu_.gyro_rad_s + a0 * (next.gyro_rad_s - prev_imu_.gyro_rad_s);
      const Eigen::Vector3d a_start =
          prev_imu_.accel_m_s2 + a0 * (next.accel_m_s2 - prev_imu_.accel_m_s2);
      m = ImuReading{0.5 * (g_start + g_end), 0.5 * (a_start + a_end)};
    }
    push_pose(m);
    propagate(belief_, m, dt, ip, inv_expo_cov);
    state_time_ = t_end;
  }
  push_pose(ImuReading{prev_imu_.gyro_rad_s, prev_imu_.accel_m_s2});
}

void LioPipeline::visual_update(const MeasurementGroup& group, MappedTime t_begin, bool lio_matched,
                                FrameReport& report) {
  const std::vector<Eigen::Vector3d>& normals = lio_matched ? p2p_->matched_normals() : no_normals_;
  const vio::RecentSweep::View sweep =
      recent_sweep_.add(t_begin, group.t_update, scan_periods_[0], world_points_, normals);
  report.vio =
      vio_->process(group.image, belief_, *sweep.points, *sweep.normals, *map_, options_.vio_debug);
  if (!report.vio.ran) {
    ++images_rejected_;
    return;
  }
  if (report.vio.updated) ++vio_updates_;
  if (options_.colorize) {
    // The scan as registered after both updates (the map export uses the same pose).
    const Eigen::Matrix3d R_wl = belief_.x.R_world_imu * options_.T_imu_lidar.linear();
    const Eigen::Vector3d p_wl =
        belief_.x.R_world_imu * options_.T_imu_lidar.translation() + belief_.x.p_world_imu;
    scan_world_.resize(undistorted_.size());
    for (std::size_t i = 0; i < undistorted_.size(); ++i) {
      scan_world_[i] = R_wl * undistorted_[i] + p_wl;
    }
    vio_->colorize(belief_.x, scan_world_, colors_, colored_);
  }
}

void LioPipeline::prepare_points(const LidarScan& scan, std::size_t lidar, MappedTime t,
                                 FrameTimings& timings) {
  const auto& lio = options_.params.lio;
  // Select points: valid, beyond the blind range, one in point_filter_num (lio/point_filter.hpp).
  // Then the voxel grid, on the raw coordinates in the LiDAR's frame: the selection depends on
  // the measured points only - not on their time stamps (undistortion), their order or where the
  // scan was cut - so every container of a recording, live or replayed, keeps the same points.
  // Undistortion then runs on the kept points only.
  auto t0 = std::chrono::steady_clock::now();
  indices_.clear();
  raw_points_.clear();
  const double blind2 = lio.blind * lio.blind;
  const auto stride = static_cast<std::uint32_t>(
      std::max(1, options_.lidar_lio[lidar].point_filter_num.value_or(lio.point_filter_num)));
  for (std::uint32_t i = 0; i < scan.size(); ++i) {
    if (!scan.valid[i]) continue;
    const Eigen::Vector3f p = scan.point(i);
    if (!point_filter_keeps(p, stride)) continue;
    const Eigen::Vector3d pd = p.cast<double>();
    if (pd.squaredNorm() < blind2) continue;
    indices_.push_back(i);
    raw_points_.push_back(pd);
  }
  timings.undistort_ms += ms_since(t0);

  t0 = std::chrono::steady_clock::now();
  if (point_budget_) {
    // The cell the budget chose. With one LiDAR a scan far over the budget is redone at once with
    // the corrected cell; with several the budget counts the frame's total (process_group) and the
    // cell follows from the next frame.
    downsampler_.set_cell(point_budget_->cell());
    kept_ = indices_;
    downsampler_.select(raw_points_, kept_);
    if (T_imu_lidars_.size() == 1 && point_budget_->observe(kept_.size())) {
      downsampler_.set_cell(point_budget_->cell());
      kept_ = indices_;
      downsampler_.select(raw_points_, kept_);
      point_budget_->observe(kept_.size());
    }
    indices_.swap(kept_);
  } else {
    downsampler_.select(raw_points_, indices_);
  }
  timings.downsample_ms += ms_since(t0);

  // Undistorted in the LiDAR's own frame, so that each point keeps its LiDAR (its ray and noise).
  t0 = std::chrono::steady_clock::now();
  undistort_points(track_, T_imu_lidars_[lidar], t, scan, indices_, lidar_points_, options_.runner);
  timings.undistort_ms += ms_since(t0);

  t0 = std::chrono::steady_clock::now();
  spatial_order_.apply(lidar_points_, lio.voxel_size);
  if (undistorted_.empty()) {
    undistorted_.swap(lidar_points_);
  } else {
    undistorted_.insert(undistorted_.end(), lidar_points_.begin(), lidar_points_.end());
  }
  point_lidar_.resize(undistorted_.size(), static_cast<std::uint32_t>(lidar));
  timings.downsample_ms += ms_since(t0);
}

void LioPipeline::process_group(const MeasurementGroup& group,
                                const std::function<void(const PipelineOutput&)>& on_output,
                                const EstimateCallback& on_estimate) {
  const auto t_total = std::chrono::steady_clock::now();
  const auto& lio = options_.params.lio;
  FrameReport report;
  const bool several = !group.scans.empty();  // several LiDARs: group.scans, one per LiDAR
  report.kind = group.kind;
  report.t = group.t_update;
  report.scan_sequence = several ? group.scan_sequence : group.scan.sequence;
  report.lidar = several ? static_cast<int>(group.lidar) : 0;
  if (several) {
    for (const LidarScan& scan : group.scans) report.raw_points += static_cast<int>(scan.size());
  } else {
    report.raw_points = static_cast<int>(group.scan.size());
  }

  const MappedTime t_begin = state_time_;  // the previous update's time
  auto t0 = std::chrono::steady_clock::now();
  propagate_to(group, track_);
  report.timings.propagate_ms = ms_since(t0);

  undistorted_.clear();
  point_lidar_.clear();
  if (several) {
    for (std::size_t l = 0; l < group.scans.size(); ++l) {
      if (!group.scans[l].empty())
        prepare_points(group.scans[l], l, group.t_update, report.timings);
    }
  } else {
    prepare_points(group.scan, 0, group.t_update, report.timings);
  }
  if (point_budget_ && T_imu_lidars_.size() > 1) {
    // The budget is per scan period of one LiDAR; n LiDARs' groups each span about a period / n
    // when their scans are not synchronised. Scans cut at the same time (phase-locked spinning
    // LiDARs, PTP-synchronised Livox) give a group of whole scans and a group of a few points
    // instead: counted per group, the cell would follow the few points down and the next whole
    // scans take 4.5x the budget (two phase-locked VLP-16s: 36 000 points, 110 ms p99).
    const Nanoseconds share = scan_periods_[0] / static_cast<std::int64_t>(T_imu_lidars_.size());
    if (share.count() > 0) {
      point_budget_->observe_part(undistorted_.size(),
                                  static_cast<double>((group.t_update - t_begin).count()) /
                                      static_cast<double>(share.count()));
    }
  }
  report.downsample_cell_m = downsampler_.cell();
  report.used_points = static_cast<int>(undistorted_.size());

  // Residuals: the points' covariances, then association and residual rows at every iteration;
  // update: the rest of the iterated update (the solves).
  t0 = std::chrono::steady_clock::now();
  scan_points_.resize(undistorted_.size());
  for_points(undistorted_.size(), [&](std::size_t begin, std::size_t end) {
    for (std::size_t i = begin; i < end; ++i) {
      scan_points_[i].p_lidar = undistorted_[i];
      // The range/bearing model of the point's own LiDAR.
      scan_points_[i].cov_lidar = point_covariance(undistorted_[i], noise_[point_lidar_[i]]);
      scan_points_[i].lidar = point_lidar_[i];
    }
  });

  double residuals_ms = ms_since(t0);
  t0 = std::chrono::steady_clock::now();
  double linearize_ms = 0.0;
  if (!map_->empty()) {
    const UpdateReport u = iterated_update(
        belief_,
        [&](const State& x, NormalEquations& eq) {
          const auto r0 = std::chrono::steady_clock::now();
          const bool ok = p2p_->linearize(scan_points_, x, eq, options_.min_matches);
          linearize_ms += ms_since(r0);
          return ok;
        },
        iteration_params(lio));
    report.iterations = u.iterations;
    report.converged = u.converged;
    report.matched = p2p_->stats().matched;
    report.updated = u.iterations > 0 && report.matched >= options_.min_matches;
    if (report.updated) {
      report.degeneracy = assess_degeneracy(u.information, options_.degeneracy_ratio);
      if (report.degeneracy.degenerate) ++counters_.degenerate_frames;
    }
  }
  if (!report.updated) ++counters_.frames_without_update;
  report.timings.update_ms = ms_since(t0) - linearize_ms;
  report.timings.residuals_ms = residuals_ms + linearize_ms;
  const bool visual = group.kind == MeasurementGroup::Kind::image && vio_;
  const auto estimate_final = [&] {
    if (on_estimate) {
      on_estimate(
          FilterEstimate{group.t_update, belief_.x, belief_.P, report.updated, report.degeneracy});
    }
  };
  if (!visual) estimate_final();

  // Map insertion with world covariances: the point's sensor noise, plus the pose uncertainty
  // with lio.map_pose_covariance (FAST-LIVO2 1.3; docs/estimator.md "Long drives": it tilts the
  // map, -1.4 mrad of pitch on a street drive).
  t0 = std::chrono::steady_clock::now();
  const Eigen::Matrix3d R = belief_.x.R_world_imu;
  Eigen::Matrix3d R_wl[kMaxLidars];
  for (std::size_t l = 0; l < T_imu_lidars_.size(); ++l) R_wl[l] = R * T_imu_lidars_[l].linear();
  const Eigen::Matrix3d P_rot = belief_.P.block<3, 3>(kRot, kRot);
  const Eigen::Matrix3d P_pos = belief_.P.block<3, 3>(kPos, kPos);
  const bool incidence = lio.incidence_term;
  const bool pose_in_map = lio.map_pose_covariance;
  const bool matched = report.iterations > 0;  // the normals are from this scan's update
  const std::vector<Eigen::Vector3d>* normals = &p2p_->matched_normals();
  world_points_.resize(scan_points_.size());
  for_points(scan_points_.size(), [&](std::size_t begin, std::size_t end) {
    for (std::size_t i = begin; i < end; ++i) {
      const Eigen::Vector3d& p_l = scan_points_[i].p_lidar;
      const std::uint32_t l = scan_points_[i].lidar;
      const Eigen::Vector3d p_i = T_imu_lidars_[l] * p_l;
      const Eigen::Matrix3d J_rot = -R * so3::hat(p_i);
      // A point that matched a plane knows its surface: its covariance gets the incidence term.
      const Eigen::Matrix3d cov_l =
          incidence && matched && !(*normals)[i].isZero()
              ? point_covariance(p_l, noise_[l],
                                 Eigen::Vector3d(R_wl[l].transpose() * (*normals)[i]))
              : scan_points_[i].cov_lidar;
      world_points_[i].p = R * p_i + belief_.x.p_world_imu;
      world_points_[i].cov = R_wl[l] * cov_l * R_wl[l].transpose();
      if (pose_in_map) world_points_[i].cov += J_rot * P_rot * J_rot.transpose() + P_pos;
    }
  });
  // Each LiDAR that builds the map and has points in this group asks its own gate.
  std::array<bool, kMaxLidars> present{};
  std::array<bool, kMaxLidars> admitted{};
  for (const ScanPoint& p : scan_points_) present[p.lidar] = true;
  bool held_back = false;
  bool all_in = true;
  for (std::size_t l = 0; l < T_imu_lidars_.size(); ++l) {
    const bool asks = present[l] && options_.lidar_lio[l].build_map;
    admitted[l] = asks && map_gates_[l].admit(t_begin, group.t_update, scan_periods_[l], R,
                                              belief_.x.p_world_imu);
    held_back = held_back || (asks && !admitted[l]);
    all_in = all_in && (admitted[l] || !present[l]);
  }
  if (held_back) ++counters_.scans_not_mapped;  // the same view again (lio.map_min_move_m)
  if (all_in) {
    map_->insert(world_points_, options_.runner);
  } else {
    // Only the points of the LiDARs that build the map (LidarLioParams::build_map) and whose
    // gate admitted this group.
    map_points_.clear();
    for (std::size_t i = 0; i < world_points_.size(); ++i) {
      if (admitted[scan_points_[i].lidar]) map_points_.push_back(world_points_[i]);
    }
    if (!map_points_.empty()) map_->insert(map_points_, options_.runner);
  }
  map_->slide(belief_.x.p_world_imu);
  report.timings.map_ms = ms_since(t0);

  colors_.clear();
  colored_.clear();
  if (visual) {
    t0 = std::chrono::steady_clock::now();
    visual_update(group, t_begin, matched, report);
    report.timings.vio_ms = ms_since(t0);
    estimate_final();
  }
  report.map = map_->stats();
  report.timings.total_ms = ms_since(t_total);
  ++counters_.scans_processed;

  if (on_output) {
    PipelineOutput out{group.t_update, belief_.x, belief_.P, report};
    out.registered_world = world_points_;
    // The pose after every update of the group (the visual one moves it in an image group).
    const Eigen::Matrix3d& R_out = belief_.x.R_world_imu;
    out.T_world_lidar.linear() = R_out * options_.T_imu_lidar.linear();
    out.T_world_lidar.translation() =
        R_out * options_.T_imu_lidar.translation() + belief_.x.p_world_imu;
    if (!colors_.empty()) {
      out.colored_world = scan_world_;
      out.colors = colors_;
      out.in_image = colored_;
    }
    if (options_.vio_debug && report.kind == MeasurementGroup::Kind::image && vio_) {
      out.vio_grey = vio_->last_grey();
    }
    on_output(out);
  }
}

}  // namespace livod::estimator
