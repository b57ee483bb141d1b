#include "estimator/vio/vio_processor.hpp"

#include <Eigen/Cholesky>
#include <algorithm>
#include <array>
#include <chrono>
#include <cmath>
#include <limits>
#include <opencv2/imgproc.hpp>

#include <time.h>

#include "core/so3.hpp"
#include "estimator/vio/photometric.hpp"
#include "estimator/vio/reference_patch.hpp"
#include "estimator/vio/warp.hpp"

namespace livod::estimator::vio {
namespace {

using Clock = std::chrono::steady_clock;

double ms_since(Clock::time_point t0) {
  return std::chrono::duration<double, std::milli>(Clock::now() - t0).count();
}

double cpu_ms(clockid_t clock) {
  timespec ts{};
  clock_gettime(clock, &ts);
  return 1e3 * static_cast<double>(ts.tv_sec) + 1e-6 * static_cast<double>(ts.tv_nsec);
}

double thread_cpu_ms() {
  return cpu_ms(CLOCK_THREAD_CPUTIME_ID);
}

constexpr float kInf = std::numeric_limits<float>::infinity();
// A point selected but failing the photometric gate this many images in a row is dropped (an
// occluder moved in front of it, or it was created on a wrong surface); its cell then gets a new
// point.
constexpr std::uint8_t kMaxFailures = 3;
// New-point candidates scored per grid cell (Shi-Tomasi costs 64 gradients each).
constexpr std::uint32_t kCandidatesPerCell = 8;

int lowest_level(std::uint32_t mask) {
  for (int l = 0; l < 32; ++l) {
    if ((mask >> l) & 1U) return l;
  }
  return -1;
}

}  // namespace

VioProcessor::VioProcessor(const VioParams& params, const MapParams& map, const VioCamera& camera,
                           TaskRunner* runner)
    : params_(params),
      runner_(runner),
      full_(camera.intrinsics),
      camera_(camera.scale == 1.0 ? camera.intrinsics : camera.intrinsics.scaled(camera.scale)),
      extrinsic_(CameraExtrinsic::from(camera.T_imu_cam)),
      map_(params.visual_voxel_size, map, static_cast<std::size_t>(params.max_visual_points)) {
  params_.pyramid_levels = std::clamp(params_.pyramid_levels, 1, kMaxPyramidLevels);
  params_.patch_size = std::clamp(params_.patch_size, 2, kMaxPatchSize);
  const auto& k = camera_.intrinsics();
  const int cell = std::max(1, params_.grid_cell_px);
  grid_cols_ = (k.width + cell - 1) / cell;
  grid_rows_ = (k.height + cell - 1) / cell;
  depth_cols_ = (k.width + kDepthCell - 1) / kDepthCell;
  depth_rows_ = (k.height + kDepthCell - 1) / kDepthCell;
  depth_.assign(static_cast<std::size_t>(depth_cols_ * depth_rows_), kInf);
  // The widest ray of the image (its border pixels), for a cheap cone test before projecting.
  double min_z = 1.0;
  for (int x = 0; x < k.width; x += 8) {
    for (const int y : {0, k.height - 1}) {
      if (const auto r = camera_.unproject({x, y})) min_z = std::min(min_z, r->z());
    }
  }
  for (int y = 0; y < k.height; y += 8) {
    for (const int x : {0, k.width - 1}) {
      if (const auto r = camera_.unproject({x, y})) min_z = std::min(min_z, r->z());
    }
  }
  // A margin of 2 deg; a lens seeing 90 deg or more off axis gets no cone test.
  const double angle = std::acos(std::clamp(min_z, -1.0, 1.0)) + 2.0 * M_PI / 180.0;
  cos_half_fov_ = angle < M_PI / 2 ? std::cos(angle) : -1.0;
}

bool VioProcessor::prepare_image(const ImageFrame& frame, VioReport& report) {
  const cv::Mat& in = frame.image;
  if (in.empty()) {
    report.problem = "empty image";
    return false;
  }
  if (in.depth() != CV_8U) {
    report.problem = "not an 8-bit image";
    return false;
  }
  if (in.cols != full_.width || in.rows != full_.height) {
    report.problem = "image size differs from the camera's configured width x height";
    return false;
  }
  const cv::Mat* grey = &in;
  cv::Mat converted;
  if (in.channels() == 3) {
    cv::cvtColor(in, converted, cv::COLOR_BGR2GRAY);
    grey = &converted;
  } else if (in.channels() == 4) {
    cv::cvtColor(in, converted, cv::COLOR_BGRA2GRAY);
    grey = &converted;
  } else if (in.channels() != 1) {
    report.problem = "unsupported channel count";
    return false;
  }
  const auto& k = camera_.intrinsics();
  if (grey->cols != k.width || grey->rows != k.height) {
    cv::Mat resized;
    cv::resize(*grey, resized, cv::Size(k.width, k.height), 0.0, 0.0, cv::INTER_AREA);
    grey_ = resized;
  } else {
    grey_ = *grey;
  }
  colour_ = in;
  pyramid_.build(grey_, params_.pyramid_levels);
  return true;
}

void VioProcessor::for_range(std::size_t n, std::size_t grain,
                             const std::function<void(std::size_t, std::size_t)>& fn) const {
  if (runner_ != nullptr) {
    parallel_for(*runner_, n, grain, fn);
  } else {
    fn(0, n);
  }
}

void VioProcessor::project_scan(const State& x, const std::vector<CovPoint>& scan_world) {
  const Eigen::Isometry3d T_cw = extrinsic_.T_world_cam(x).inverse();
  const Eigen::Matrix3d R = T_cw.linear();
  const Eigen::Vector3d t = T_cw.translation();
  const std::size_t n = scan_world.size();
  scan_px_.resize(n);
  scan_range_.resize(n);
  scan_point_keys_.resize(n);
  const double cos_fov = cos_half_fov_;
  for_range(n, 2048, [&](std::size_t begin, std::size_t end) {
    for (std::size_t i = begin; i < end; ++i) {
      scan_range_[i] = -1.0F;
      const Eigen::Vector3d pc = R * scan_world[i].p + t;
      if (pc.z() <= 0.05) continue;
      // Outside the cone around the optical axis that holds the image: no projection needed.
      // Squared (z > 0 here): no square root for the points behind or beside the camera. The
      // cone has a 2 deg margin around the image, so rounding at its edge changes nothing.
      const double norm2 = pc.squaredNorm();
      if (cos_fov > 0.0 && pc.z() * pc.z() < cos_fov * cos_fov * norm2) continue;
      const auto px = camera_.project(pc);
      if (!px || !camera_.in_image(*px)) continue;
      scan_px_[i] = px->cast<float>();
      scan_range_[i] = static_cast<float>(std::sqrt(norm2));
      scan_point_keys_[i] = map_.key(scan_world[i].p);
    }
  });
  // The visual voxels to look in: those of the scan's points in the image (FAST-LIVO2 takes the
  // voxels of the whole scan; the others hold nothing the camera sees).
  // In the same pass, the sparse depth image: the nearest LiDAR return per cell.
  scan_keys_.clear();
  std::fill(depth_.begin(), depth_.end(), kInf);
  for (std::size_t i = 0; i < n; ++i) {
    if (scan_range_[i] < 0.0F) continue;
    scan_keys_.push_back(scan_point_keys_[i]);
    const int cx = static_cast<int>(scan_px_[i].x()) / kDepthCell;
    const int cy = static_cast<int>(scan_px_[i].y()) / kDepthCell;
    float& d = depth_[static_cast<std::size_t>(cy * depth_cols_ + cx)];
    d = std::min(d, scan_range_[i]);
  }
}

bool VioProcessor::near_depth_jump(const Eigen::Vector2d& px, double depth) const {
  // FAST-LIVO2 looks at the LiDAR depths in the 9x9 pixels around the point.
  constexpr double kReach = 4.0;
  const int x0 = std::max(0, static_cast<int>(std::floor((px.x() - kReach) / kDepthCell)));
  const int x1 =
      std::min(depth_cols_ - 1, static_cast<int>(std::floor((px.x() + kReach) / kDepthCell)));
  const int y0 = std::max(0, static_cast<int>(std::floor((px.y() - kReach) / kDepthCell)));
  const int y1 =
      std::min(depth_rows_ - 1, static_cast<int>(std::floor((px.y() + kReach) / kDepthCell)));
  const auto thr = static_cast<float>(params_.depth_discontinuity_m);
  const auto d = static_cast<float>(depth);
  for (int y = y0; y <= y1; ++y) {
    for (int x = x0; x <= x1; ++x) {
      const float l = depth_[static_cast<std::size_t>(y * depth_cols_ + x)];
      if (l != kInf && std::abs(l - d) > thr) return true;
    }
  }
  return false;
}

bool VioProcessor::warp_reference(const State& x, Patch& patch, float* out) const {
  const VisualPoint& vp = map_.at(patch.id);
  const PatchObservation& ref = vp.observations[vp.reference];
  const int P = params_.patch_size;
  const int L = params_.pyramid_levels;
  const Eigen::Isometry3d T_wr = ref.T_world_cam();
  const Eigen::Isometry3d T_cur_ref = extrinsic_.T_world_cam(x).inverse() * T_wr;
  const Eigen::Vector3d p_ref = T_wr.inverse() * vp.p_world;
  const Eigen::Vector3d n_ref = params_.normal_en
                                    ? Eigen::Vector3d(T_wr.linear().transpose() * vp.normal)
                                    : Eigen::Vector3d(-p_ref.normalized());
  const auto A = affine_warp(camera_, T_cur_ref, p_ref, n_ref);
  if (!A || std::abs(A->determinant()) < 1e-6) return false;
  const Eigen::Matrix2d A_ref_cur = A->inverse();
  const std::size_t n = static_cast<std::size_t>(P * P);
  patch.level_mask = 0;
  for (int l = 0; l < L; ++l) {
    if (warp_reference_patch(ref, A_ref_cur, l, L, P, out + static_cast<std::size_t>(l) * n)) {
      patch.level_mask |= 1U << l;
    }
  }
  return patch.level_mask != 0;
}

void VioProcessor::select(const State& x, VioReport& report) {
  const int P = params_.patch_size;
  const int L = params_.pyramid_levels;
  const std::size_t cells = static_cast<std::size_t>(grid_cols_ * grid_rows_);
  patches_.clear();
  refs_.clear();
  cell_point_.assign(cells, -1);
  cell_depth_.assign(cells, kInf);
  map_.gather(scan_keys_, candidates_);
  const Eigen::Isometry3d T_wc = extrinsic_.T_world_cam(x);
  const Eigen::Isometry3d T_cw = T_wc.inverse();
  const double border = 0.5 * P + 1.0;
  const int cell_px = std::max(1, params_.grid_cell_px);
  // Closest candidate per cell (FAST-LIVO2), remembered by its index in candidates_.
  for (std::size_t c = 0; c < candidates_.size(); ++c) {
    const VisualPoint& vp = map_.at(candidates_[c]);
    if (!vp.alive || vp.observations.empty()) continue;
    const Eigen::Vector3d pc = T_cw * vp.p_world;
    const auto px = camera_.project(pc);
    if (!px || !camera_.in_image(*px, border)) continue;
    ++report.candidates;
    const int cell =
        static_cast<int>(px->y()) / cell_px * grid_cols_ + static_cast<int>(px->x()) / cell_px;
    const auto depth = static_cast<float>(pc.norm());
    if (depth < cell_depth_[static_cast<std::size_t>(cell)]) {
      cell_depth_[static_cast<std::size_t>(cell)] = depth;
      cell_point_[static_cast<std::size_t>(cell)] = static_cast<std::int32_t>(c);
    }
  }
  const double cos_max = std::cos(params_.max_view_angle_deg * M_PI / 180.0);
  const std::size_t per_patch = static_cast<std::size_t>(L * P * P);
  for (std::size_t cell = 0; cell < cells; ++cell) {
    if (cell_point_[cell] < 0) continue;
    const std::uint32_t id = candidates_[static_cast<std::size_t>(cell_point_[cell])];
    const VisualPoint& vp = map_.at(id);
    const Eigen::Vector3d pc = T_cw * vp.p_world;
    const Eigen::Vector2d px = *camera_.project(pc);
    const double depth = pc.norm();
    if (near_depth_jump(px, depth)) continue;
    const Eigen::Vector3d ray = (vp.p_world - T_wc.translation()) / depth;
    if (-ray.dot(vp.normal) < cos_max) continue;
    Patch patch;
    patch.id = id;
    patch.p_world = vp.p_world;
    patch.px = px;
    patch.depth = depth;
    patch.cell = static_cast<int>(cell);
    patch.ref_offset = refs_.size();
    refs_.resize(refs_.size() + per_patch);
    patches_.push_back(patch);
  }
  // The reference warps (most of the selection's time) are independent: one slot each. A patch
  // whose warp fails at every level is dropped afterwards, in order (its refs_ slot stays unused).
  for_range(patches_.size(), 16, [&](std::size_t begin, std::size_t end) {
    for (std::size_t i = begin; i < end; ++i) {
      Patch& patch = patches_[i];
      warp_reference(x, patch, refs_.data() + patch.ref_offset);
    }
  });
  patches_.erase(std::remove_if(patches_.begin(), patches_.end(),
                                [](const Patch& p) { return p.level_mask == 0; }),
                 patches_.end());
  report.selected = static_cast<int>(patches_.size());
}

double VioProcessor::gate(const State& x, VioReport& report) {
  const int P = params_.patch_size;
  const std::size_t n = static_cast<std::size_t>(P * P);
  // The exposure change first, robustly (median of the patches' mean ratios): a camera's auto
  // exposure doubling the brightness would otherwise fail every patch at the gate.
  // Each patch's mean ratio in its own slot (NaN: none), collected in patch order afterwards.
  gate_evals_.resize(patches_.size());
  gate_ratios_.resize(patches_.size());
  for_range(patches_.size(), 16, [&](std::size_t begin, std::size_t end) {
    for (std::size_t i = begin; i < end; ++i) {
      const Patch& p = patches_[i];
      const int l = lowest_level(p.level_mask);
      PatchEval& ev = gate_evals_[i];
      gate_ratios_[i] = std::numeric_limits<double>::quiet_NaN();
      if (!evaluate_patch(pyramid_.level(l), l, P, p.px, 1.0, nullptr, ev)) {
        ev.pixels = 0;
        continue;
      }
      double cur = 0.0;
      double ref = 0.0;
      const float* r = refs_.data() + p.ref_offset + static_cast<std::size_t>(l) * n;
      for (std::size_t k = 0; k < n; ++k) {
        cur += ev.intensity[k];
        ref += r[k];
      }
      if (cur > static_cast<double>(n)) gate_ratios_[i] = ref / cur;
    }
  });
  ratios_.clear();
  for (const double ratio : gate_ratios_) {
    if (!std::isnan(ratio)) ratios_.push_back(ratio);
  }
  double tau = x.inv_exposure;
  if (params_.exposure_estimate && static_cast<int>(ratios_.size()) >= params_.min_patches) {
    const auto mid = ratios_.begin() + static_cast<std::ptrdiff_t>(ratios_.size() / 2);
    std::nth_element(ratios_.begin(), mid, ratios_.end());
    tau = *mid;
  }
  double sq = 0.0;
  int used = 0;
  const auto t = static_cast<float>(tau);
  for (std::size_t i = 0; i < patches_.size(); ++i) {
    Patch& p = patches_[i];
    if (gate_evals_[i].pixels == 0) continue;
    const int l = lowest_level(p.level_mask);
    const float* r = refs_.data() + p.ref_offset + static_cast<std::size_t>(l) * n;
    const PatchEval& ev = gate_evals_[i];
    double mse = 0.0;
    for (std::size_t k = 0; k < n; ++k) {
      const double d = t * ev.intensity[k] - r[k];
      mse += d * d;
    }
    mse /= static_cast<double>(n);
    p.rms_before = static_cast<float>(std::sqrt(mse));
    if (mse > params_.outlier_threshold) {
      ++report.rejected_outlier;
      VisualPoint& vp = map_.at(p.id);
      if (++vp.failures >= kMaxFailures) map_.remove(p.id);
      continue;
    }
    p.used = true;
    sq += mse;
    ++used;
  }
  report.patches = used;
  report.rms_before = used > 0 ? std::sqrt(sq / used) : 0.0;
  return tau;
}

void VioProcessor::update(Belief& belief, double tau_start, VioReport& report) {
  if (report.patches < params_.min_patches) return;
  const int P = params_.patch_size;
  const std::size_t n = static_cast<std::size_t>(P * P);
  const double sigma2 = params_.img_point_cov;
  const double huber = params_.huber_k > 0.0 ? params_.huber_k * std::sqrt(sigma2) : 0.0;
  const double conv_rot = params_.convergence.rotation_deg * M_PI / 180.0;
  const double conv_pos = params_.convergence.translation_m;
  const State prior = belief.x;
  const StateMatrix P_inv = belief.P.inverse();
  State x = prior;
  if (params_.exposure_estimate) x.inv_exposure = tau_start;
  StateMatrix A_last = StateMatrix::Zero();
  bool have_step = false;
  for (int level = params_.pyramid_levels - 1; level >= 0; --level) {
    double last_cost = std::numeric_limits<double>::infinity();
    State x_prev = x;
    StateMatrix A_prev = A_last;
    for (int it = 0; it < params_.max_iterations; ++it) {
      // Patches in fixed blocks, summed in block order: the same sums for any thread count.
      constexpr std::size_t kBlock = 16;
      const std::size_t blocks = (patches_.size() + kBlock - 1) / kBlock;
      block_sums_.assign(blocks, PatchNormals{});
      for_range(blocks, 1, [&](std::size_t b0, std::size_t b1) {
        PatchEval e;
        for (std::size_t b = b0; b < b1; ++b) {
          PatchNormals& acc = block_sums_[b];
          const std::size_t end = std::min(patches_.size(), (b + 1) * kBlock);
          for (std::size_t i = b * kBlock; i < end; ++i) {
            const Patch& p = patches_[i];
            if (!p.used || ((p.level_mask >> level) & 1U) == 0) continue;
            PoseJacobian J;
            const auto px = project_from_state(camera_, extrinsic_, x, p.p_world, &J);
            if (!px) continue;
            const float* ref = refs_.data() + p.ref_offset + static_cast<std::size_t>(level) * n;
            if (!evaluate_patch(pyramid_.level(level), level, P, *px, x.inv_exposure, ref, e)) {
              continue;
            }
            accumulate_patch(e, J, huber, params_.exposure_estimate, acc);
          }
        }
      });
      PatchNormals sum;
      for (const auto& b : block_sums_) {
        sum.HtWH += b.HtWH;
        sum.HtWr += b.HtWr;
        sum.cost += b.cost;
        sum.sq_error += b.sq_error;
        sum.pixels += b.pixels;
      }
      if (sum.pixels == 0) break;
      const double cost = sum.cost / sum.pixels;
      if (cost > last_cost) {
        // The step made the error worse: back to the previous iterate, next level.
        x = x_prev;
        A_last = A_prev;
        break;
      }
      const StateVector delta = x.boxminus(prior);
      StateMatrix Jr = StateMatrix::Identity();
      Jr.block<3, 3>(kRot, kRot) = so3::right_jacobian_inverse(delta.segment<3>(kRot));
      const StateMatrix JtPinv = Jr.transpose() * P_inv;
      StateMatrix A = JtPinv * Jr;
      A.topLeftCorner<7, 7>() += sum.HtWH / sigma2;
      StateVector b = -JtPinv * delta;
      // z = 0 - r: the rows' right-hand side is -H^T W r.
      b.head<7>() -= sum.HtWr / sigma2;
      const StateVector dx = A.ldlt().solve(b);
      x_prev = x;
      A_prev = A;
      A_last = A;
      last_cost = cost;
      have_step = true;
      x = x.boxplus(dx);
      ++report.iterations;
      if (dx.segment<3>(kRot).norm() < conv_rot && dx.segment<3>(kPos).norm() < conv_pos) break;
    }
  }
  if (!have_step) return;
  belief.x = x;
  const StateMatrix Pn = A_last.inverse();
  belief.P = 0.5 * (Pn + Pn.transpose());
  report.updated = true;
}

bool VioProcessor::capture(const State& x, const Eigen::Vector2d& px, PatchObservation& obs) const {
  if (!capture_blocks(pyramid_, px, params_.patch_size, obs)) return false;
  const Eigen::Isometry3d T_wc = extrinsic_.T_world_cam(x);
  obs.q_world_cam = Eigen::Quaterniond(T_wc.linear()).normalized();
  obs.p_world_cam = T_wc.translation();
  obs.pixel = px;
  obs.inv_exposure = static_cast<float>(x.inv_exposure);
  obs.score = 0.0F;
  return true;
}

void VioProcessor::unit_patch(const PatchObservation& obs, float* out) const {
  const int P = params_.patch_size;
  const int S = block_edge(P);
  const std::size_t n = static_cast<std::size_t>(P * P);
  const int start = (S - P) / 2;
  const std::uint8_t* b = obs.block(0, S);
  if (P == 8) {
    // 64 pixels: the mean is a multiple of 1/64, so every centred value v - mean is exact in
    // float (d / 64 with d = 64 v - sum) and the double sum of their squares is exact too (at
    // most 34 significant bits): integers give the same values as the general loop below.
    std::int32_t sum8 = 0;
    std::array<std::int32_t, 64> d;  // NOLINT: written below
    for (int y = 0; y < 8; ++y) {
      for (int x = 0; x < 8; ++x) {
        d[static_cast<std::size_t>(y * 8 + x)] = b[(start + y) * S + start + x];
      }
    }
    for (const std::int32_t v : d) sum8 += v;
    std::int64_t sq = 0;
    for (std::int32_t& v : d) {
      v = 64 * v - sum8;
      sq += static_cast<std::int64_t>(v) * v;
    }
    const double norm = static_cast<double>(sq) / 4096.0;
    const float inv = norm > 1e-9 ? static_cast<float>(1.0 / std::sqrt(norm)) : 0.0F;
    for (std::size_t k = 0; k < 64; ++k) {
      out[k] = static_cast<float>(d[k]) * (1.0F / 64.0F) * inv;
    }
    return;
  }
  std::uint32_t sum = 0;  // exact, as the double sum of the pixels is
  for (int y = 0; y < P; ++y) {
    for (int x = 0; x < P; ++x) {
      const std::uint8_t v = b[(start + y) * S + start + x];
      out[y * P + x] = static_cast<float>(v);
      sum += v;
    }
  }
  const double mean = static_cast<double>(sum) / static_cast<double>(n);
  double norm = 0.0;
  for (std::size_t k = 0; k < n; ++k) {
    out[k] -= static_cast<float>(mean);
    norm += static_cast<double>(out[k]) * out[k];
  }
  const float inv = norm > 1e-9 ? static_cast<float>(1.0 / std::sqrt(norm)) : 0.0F;
  for (std::size_t k = 0; k < n; ++k) out[k] *= inv;
}

void VioProcessor::add_observation(VisualPoint& point, PatchObservation obs,
                                   std::vector<float>& work) const {
  auto& all = point.observations;
  const std::size_t n = static_cast<std::size_t>(params_.patch_size * params_.patch_size);
  // The level-0 unit patches of the point's observations, slot i for all[i] and the new one last,
  // computed once for the scores and for the eviction below.
  const std::size_t m = all.size();
  work.resize((m + 1) * n);
  auto unit = [&](std::size_t i) { return work.data() + i * n; };
  auto abs_dot = [n](const float* a, const float* b) {
    float dot = 0.0F;
    for (std::size_t k = 0; k < n; ++k) dot += a[k] * b[k];
    return std::abs(dot);
  };
  // FAST-LIVO2's reference score: mean |NCC| of the level-0 patch with the point's other patches
  // plus the cosine of the viewing angle. The NCC sums are kept per patch and updated for the one
  // added and the one dropped (O(n) patch products instead of O(n^2)).
  unit_patch(obs, unit(m));
  obs.ncc_sum = 0.0F;
  for (std::size_t i = 0; i < m; ++i) {
    unit_patch(all[i], unit(i));
    const float d = abs_dot(unit(m), unit(i));
    all[i].ncc_sum += d;
    obs.ncc_sum += d;
  }
  all.push_back(std::move(obs));
  auto score_all = [&] {
    std::size_t best = 0;
    const double others = static_cast<double>(std::max<std::size_t>(1, all.size() - 1));
    for (std::size_t i = 0; i < all.size(); ++i) {
      const Eigen::Vector3d ray = (point.p_world - all[i].p_world_cam).normalized();
      all[i].score = static_cast<float>(all[i].ncc_sum / others + std::abs(ray.dot(point.normal)));
      if (all[i].score > all[best].score) best = i;
    }
    return best;
  };
  std::size_t best = score_all();
  if (all.size() > static_cast<std::size_t>(params_.max_observations)) {
    // Drop the lowest-scoring patch that is not the best one.
    std::size_t worst = best == 0 ? 1 : 0;
    for (std::size_t i = 0; i < all.size(); ++i) {
      if (i != best && all[i].score < all[worst].score) worst = i;
    }
    for (std::size_t i = 0; i < all.size(); ++i) {
      if (i == worst) continue;
      all[i].ncc_sum = std::max(0.0F, all[i].ncc_sum - abs_dot(unit(worst), unit(i)));
    }
    all.erase(all.begin() + static_cast<std::ptrdiff_t>(worst));
    best = score_all();
  }
  point.reference = static_cast<std::uint32_t>(best);
}

void VioProcessor::refine_normal(VisualPoint& point, const Eigen::Vector3d& camera_center,
                                 const VoxelMap& lidar_map) const {
  PlaneMatch m;
  if (!lidar_map.match(point.p_world, Eigen::Matrix3d::Identity() * 1e-4, m) ||
      m.plane == nullptr) {
    return;
  }
  Eigen::Vector3d n = m.plane->normal;
  if (n.dot(camera_center - point.p_world) < 0.0) n = -n;
  point.normal = n;
}

void VioProcessor::maintain(const State& x, const std::vector<CovPoint>& scan_world,
                            const std::vector<Eigen::Vector3d>& scan_normals,
                            const VoxelMap& lidar_map, VioReport& report) {
  const int P = params_.patch_size;
  const int L = params_.pyramid_levels;
  const int S = block_edge(P);
  const std::size_t n = static_cast<std::size_t>(P * P);
  const std::size_t cells = static_cast<std::size_t>(grid_cols_ * grid_rows_);
  const int cell_px = std::max(1, params_.grid_cell_px);
  const Eigen::Isometry3d T_wc = extrinsic_.T_world_cam(x);
  const Eigen::Isometry3d T_cw = T_wc.inverse();
  const Eigen::Vector3d center = T_wc.translation();
  const Eigen::Quaterniond q_wc(T_wc.linear());
  const double obs_angle = params_.observation_angle_deg * M_PI / 180.0;
  std::vector<std::uint8_t>& occupied = occupied_;
  occupied.assign(cells, 0);
  // The photometric error after the update, per patch in its own slots (independent work).
  for_range(patches_.size(), 16, [&](std::size_t begin, std::size_t end) {
    PatchEval e;
    for (std::size_t i = begin; i < end; ++i) {
      Patch& p = patches_[i];
      p.mse_after = -1.0;
      if (!p.used) continue;
      const auto px = project_from_state(camera_, extrinsic_, x, p.p_world);
      if (!px) continue;
      const int l = lowest_level(p.level_mask);
      const float* ref = refs_.data() + p.ref_offset + static_cast<std::size_t>(l) * n;
      if (!evaluate_patch(pyramid_.level(l), l, P, *px, x.inv_exposure, ref, e)) continue;
      double mse = 0.0;
      for (std::size_t k = 0; k < n; ++k) {
        mse += static_cast<double>(e.residual[k]) * e.residual[k];
      }
      p.px_after = *px;
      p.mse_after = mse / static_cast<double>(n);
    }
  });
  double sq_after = 0.0;
  int tracked = 0;
  observe_.clear();
  for (const Patch& p : patches_) {
    if (!p.used) {
      if (debug_) {
        report.debug.push_back(
            {p.px.cast<float>(), VioPatchDebug::Status::rejected, p.rms_before, p.rms_before});
      }
      continue;
    }
    if (p.mse_after < 0.0) continue;
    VisualPoint& vp = map_.at(p.id);
    const Eigen::Vector2d* px = &p.px_after;
    const double mse = p.mse_after;
    const bool ok = mse <= params_.outlier_threshold;
    if (debug_) {
      report.debug.push_back({px->cast<float>(),
                              ok ? VioPatchDebug::Status::tracked : VioPatchDebug::Status::rejected,
                              p.rms_before, static_cast<float>(std::sqrt(mse))});
    }
    if (!ok) {
      if (++vp.failures >= kMaxFailures) map_.remove(p.id);
      continue;
    }
    sq_after += mse;
    ++tracked;
    vp.failures = 0;
    vp.last_seen = frame_;
    if (camera_.in_image(*px)) {
      occupied[static_cast<std::size_t>(static_cast<int>(px->y()) / cell_px * grid_cols_ +
                                        static_cast<int>(px->x()) / cell_px)] = 1;
    }
    // A new reference patch when the point is seen from elsewhere (FAST-LIVO2's rule).
    const PatchObservation& last = vp.observations.back();
    const bool moved = (center - last.p_world_cam).norm() > params_.observation_distance_m ||
                       q_wc.angularDistance(last.q_world_cam) > obs_angle ||
                       (*px - last.pixel).norm() > params_.observation_pixels;
    if (moved) observe_.push_back(static_cast<std::uint32_t>(&p - patches_.data()));
  }
  report.rms_after = tracked > 0 ? std::sqrt(sq_after / tracked) : 0.0;
  // The new reference patches: each touches its own point only (and reads the image and the
  // LiDAR map), so the points are done in parallel, with the same result as one after the other.
  observed_.assign(observe_.size(), 0);
  for_range(observe_.size(), 8, [&](std::size_t begin, std::size_t end) {
    std::vector<float> work;
    for (std::size_t k = begin; k < end; ++k) {
      const Patch& p = patches_[observe_[k]];
      VisualPoint& vp = map_.at(p.id);
      PatchObservation obs;
      if (!capture(x, p.px_after, obs)) continue;
      observed_[k] = 1;
      refine_normal(vp, center, lidar_map);
      add_observation(vp, std::move(obs), work);
    }
  });
  for (const auto o : observed_) report.new_observations += o;

  // New points in the cells left empty: the LiDAR point with a plane and the best corner score.
  std::vector<float>& best_score = cell_depth_;  // reused as the per-cell best score
  best_score.assign(cells, -1.0F);
  std::vector<std::int32_t>& best_index = cell_point_;
  best_index.assign(cells, -1);
  std::vector<std::uint8_t>& tried = cell_tried_;
  tried.assign(cells, 0);
  const double border = (0.5 * S + 1.0) * std::ldexp(1.0, L - 1);
  // Cells from the scan's pixels at the prior pose (the update moves them by a fraction of a
  // pixel); a new point's own pixel is computed again at the updated pose below. The candidates
  // of a cell are counted first, so that the ones scored (Shi-Tomasi costs 64 gradients each)
  // are spread over the cell instead of being its first, neighbouring, points.
  auto cell_of = [&](std::size_t i) -> std::int64_t {
    if (scan_range_[i] < 0.0F || i >= scan_normals.size() || scan_normals[i].isZero()) return -1;
    const Eigen::Vector2d px = scan_px_[i].cast<double>();
    if (!camera_.in_image(px, border)) return -1;
    const auto cell = static_cast<std::size_t>(static_cast<int>(px.y()) / cell_px * grid_cols_ +
                                               static_cast<int>(px.x()) / cell_px);
    return occupied[cell] != 0 ? -1 : static_cast<std::int64_t>(cell);
  };
  std::vector<std::uint32_t>& count = cell_count_;
  count.assign(cells, 0);
  const std::size_t points = std::min(scan_world.size(), scan_normals.size());
  // Each point's cell once (in parallel), for the two passes below.
  scan_cell_.resize(points);
  for_range(points, 2048, [&](std::size_t begin, std::size_t end) {
    for (std::size_t i = begin; i < end; ++i) scan_cell_[i] = cell_of(i);
  });
  for (std::size_t i = 0; i < points; ++i) {
    if (const auto c = scan_cell_[i]; c >= 0) ++count[static_cast<std::size_t>(c)];
  }
  std::vector<std::uint32_t>& seen = cell_seen_;
  seen.assign(cells, 0);
  // Which points are scored is decided first; the scores (independent) are computed in their own
  // slots, then each cell keeps its best in point order.
  scored_.clear();
  for (std::size_t i = 0; i < points; ++i) {
    const auto c = scan_cell_[i];
    if (c < 0) continue;
    const auto cell = static_cast<std::size_t>(c);
    const std::uint32_t stride = std::max<std::uint32_t>(1, count[cell] / kCandidatesPerCell);
    if (seen[cell]++ % stride != 0 || tried[cell] >= kCandidatesPerCell) continue;
    ++tried[cell];
    scored_.push_back({static_cast<std::uint32_t>(i), static_cast<std::uint32_t>(cell), 0.0F});
  }
  for_range(scored_.size(), 64, [&](std::size_t begin, std::size_t end) {
    for (std::size_t k = begin; k < end; ++k) {
      scored_[k].score =
          static_cast<float>(shi_tomasi_score(grey_, scan_px_[scored_[k].point].cast<double>(), P));
    }
  });
  for (const auto& c : scored_) {
    if (c.score > best_score[c.cell]) {
      best_score[c.cell] = c.score;
      best_index[c.cell] = static_cast<std::int32_t>(c.point);
    }
  }
  const double cos_max = std::cos(params_.max_view_angle_deg * M_PI / 180.0);
  for (std::size_t cell = 0; cell < cells; ++cell) {
    if (best_index[cell] < 0 || best_score[cell] < params_.min_corner_score) continue;
    const auto i = static_cast<std::size_t>(best_index[cell]);
    VisualPoint vp;
    vp.p_world = scan_world[i].p;
    vp.normal = scan_normals[i].normalized();
    // On the LiDAR map's plane (mm-level) rather than the single noisy return, when it has one.
    PlaneMatch m;
    if (lidar_map.match(vp.p_world, Eigen::Matrix3d::Identity() * 1e-4, m) && m.plane != nullptr) {
      vp.p_world -= m.distance * m.plane->normal;
      vp.normal = m.plane->normal;
    }
    if (vp.normal.dot(center - vp.p_world) < 0.0) vp.normal = -vp.normal;
    const Eigen::Vector3d pc = T_cw * vp.p_world;
    const auto px = camera_.project(pc);
    if (!px || !camera_.in_image(*px, border)) continue;
    const double depth = pc.norm();
    if (near_depth_jump(*px, depth)) continue;
    if ((center - vp.p_world).dot(vp.normal) / depth < cos_max) continue;
    PatchObservation obs;
    if (!capture(x, *px, obs)) continue;
    vp.observations.push_back(std::move(obs));
    vp.last_seen = frame_;
    map_.add(std::move(vp));
    ++report.new_points;
    if (debug_) {
      report.debug.push_back({px->cast<float>(), VioPatchDebug::Status::created, 0.0F, 0.0F});
    }
  }
  map_.slide(x.p_world_imu);
  map_.enforce_budget();
}

VioReport VioProcessor::process(const ImageFrame& frame, Belief& belief,
                                const std::vector<CovPoint>& scan_world,
                                const std::vector<Eigen::Vector3d>& scan_normals,
                                const VoxelMap& lidar_map, bool debug) {
  const auto t_total = Clock::now();
  const double cpu0 = thread_cpu_ms();
  const double process_cpu0 = cpu_ms(CLOCK_PROCESS_CPUTIME_ID);
  VioReport report;
  debug_ = debug;
  auto t0 = Clock::now();
  double c0 = cpu0;
  auto lap = [&](double& wall, double& cpu) {
    const double c = thread_cpu_ms();
    wall = ms_since(t0);
    cpu = c - c0;
    t0 = Clock::now();
    c0 = c;
  };
  if (!prepare_image(frame, report)) return report;
  report.ran = true;
  ++frame_;
  lap(report.timings.pyramid_ms, report.timings.pyramid_cpu_ms);

  project_scan(belief.x, scan_world);
  select(belief.x, report);
  const double tau_start = gate(belief.x, report);
  lap(report.timings.selection_ms, report.timings.selection_cpu_ms);

  update(belief, tau_start, report);
  lap(report.timings.update_ms, report.timings.update_cpu_ms);

  maintain(belief.x, scan_world, scan_normals, lidar_map, report);
  if (frame_ % 10 == 1) map_stats_ = map_.stats();
  report.map = map_stats_;
  lap(report.timings.map_ms, report.timings.map_cpu_ms);
  report.inv_exposure = belief.x.inv_exposure;
  report.timings.total_ms = ms_since(t_total);
  report.timings.cpu_ms = thread_cpu_ms() - cpu0;
  report.timings.process_cpu_ms = cpu_ms(CLOCK_PROCESS_CPUTIME_ID) - process_cpu0;
  return report;
}

void VioProcessor::colorize(const State& x, const std::vector<Eigen::Vector3d>& p_world,
                            std::vector<std::uint32_t>& rgb,
                            std::vector<std::uint8_t>& seen) const {
  rgb.assign(p_world.size(), 0);
  seen.assign(p_world.size(), 0);
  if (colour_.empty()) return;
  const CameraModel full(full_);
  const Eigen::Isometry3d T_cw = extrinsic_.T_world_cam(x).inverse();
  const bool bgr = colour_.channels() >= 3;
  for (std::size_t i = 0; i < p_world.size(); ++i) {
    const auto px = full.project(T_cw * p_world[i]);
    if (!px || !full.in_image(*px)) continue;
    const int u = static_cast<int>(std::lround(px->x()));
    const int v = static_cast<int>(std::lround(px->y()));
    const std::uint8_t* row = colour_.ptr<std::uint8_t>(v);
    std::uint32_t r = 0, g = 0, b = 0;
    if (bgr) {
      const std::uint8_t* c = row + static_cast<std::ptrdiff_t>(u) * colour_.channels();
      b = c[0];
      g = c[1];
      r = c[2];
    } else {
      r = g = b = row[u];
    }
    rgb[i] = (r << 16) | (g << 8) | b;
    seen[i] = 1;
  }
}

}  // namespace livod::estimator::vio
