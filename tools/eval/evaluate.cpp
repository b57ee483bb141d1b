#include "tools/eval/evaluate.hpp"

#include <fmt/format.h>

#include <numbers>

#include "core/error.hpp"
#include "core/so3.hpp"

namespace livod::eval {
namespace {

std::string stats_line(std::string_view label, const ErrorStatistics& s, std::string_view unit,
                       const std::string& what) {
  return fmt::format(
      "{}  RMSE {:.6f} {}  mean {:.6f} {}  median {:.6f} {}  std {:.6f} {}  min {:.6f} {}  max "
      "{:.6f} {}  ({})\n",
      label, s.rmse, unit, s.mean, unit, s.median, unit, s.std, unit, s.min, unit, s.max, unit,
      what);
}

std::string delta_text(const EvalOptions& o) {
  return fmt::format("delta {:g} {}", o.rpe_delta, to_string(o.rpe_unit));
}

}  // namespace

EvalResult evaluate(const Trajectory& gt, const Trajectory& est, const EvalOptions& options) {
  if (gt.empty()) throw Error("the ground truth has no poses");
  if (est.empty()) throw Error("the estimate has no poses");
  EvalResult r;
  r.gt_poses_read = gt.size();
  r.est_poses_read = est.size();

  // KITTI pairs pose i with pose i even with a times file: both files index the same frames.
  const bool by_time = options.format != TrajectoryFormat::kKitti;
  const Association a =
      by_time ? associate_by_time(gt, est, options.max_time_diff_s, options.time_offset_s)
              : associate_by_index(gt, est);
  r.associated_by_time = by_time;
  r.gt = gt.subset(a.gt_index);
  const Trajectory est_assoc = est.subset(a.est_index);

  r.alignment = align(r.gt, est_assoc, options.alignment);
  r.est_aligned = transformed(est_assoc, r.alignment);

  r.ape_m = absolute_translation_errors(r.gt, r.est_aligned);
  r.ape = compute_statistics(r.ape_m);

  // Pairs are chosen on the (aligned) estimate, as evo does by default.
  const std::vector<IndexPair> pairs =
      select_rpe_pairs(r.est_aligned, options.rpe_delta, options.rpe_unit);
  r.rpe = relative_pose_errors(r.gt, r.est_aligned, pairs);
  if (!pairs.empty()) {
    r.rpe_translation = compute_statistics(r.rpe.translation_m);
    r.rpe_rotation = compute_statistics(r.rpe.rotation_deg);
  }
  return r;
}

EvalResult evaluate_files(const std::filesystem::path& est_path,
                          const std::filesystem::path& gt_path, const EvalOptions& options) {
  Trajectory gt;
  Trajectory est;
  switch (options.format) {
    case TrajectoryFormat::kTum:
      gt = read_tum(gt_path);
      est = read_tum(est_path);
      break;
    case TrajectoryFormat::kKitti:
      gt = read_kitti(gt_path, options.kitti_times);
      est = read_kitti(est_path, options.kitti_times);
      break;
    case TrajectoryFormat::kEuroc:
      gt = read_euroc_csv(gt_path);
      est = read_tum(est_path);
      break;
  }
  return evaluate(gt, est, options);
}

std::string format_report(const EvalResult& r, const EvalOptions& o) {
  std::string out;
  out +=
      fmt::format("poses        ground truth {}, estimate {}\n", r.gt_poses_read, r.est_poses_read);
  if (r.associated_by_time) {
    out += fmt::format("association  {} pairs by time (max diff {:g} s, offset {:g} s)\n",
                       r.gt.size(), o.max_time_diff_s, o.time_offset_s);
  } else {
    out += fmt::format("association  {} pairs by index\n", r.gt.size());
  }
  const Eigen::Vector3d& t = r.alignment.translation;
  out += fmt::format(
      "alignment    {}: rotation {:.4f} deg, translation [{:.4f} {:.4f} {:.4f}] m, scale {:.6f}\n",
      to_string(o.alignment), so3::angle(r.alignment.rotation) * 180.0 / std::numbers::pi, t.x(),
      t.y(), t.z(), r.alignment.scale);
  out += stats_line("ATE", r.ape, "m", fmt::format("{} poses", r.ape.count));
  if (r.rpe_translation && r.rpe_rotation) {
    const std::string what = fmt::format("{} pairs, {}", r.rpe_translation->count, delta_text(o));
    out += stats_line("RPE", *r.rpe_translation, "m", what + ", translation");
    out += stats_line("RPE", *r.rpe_rotation, "deg", what + ", rotation");
  } else {
    out += fmt::format("RPE  no pose pair for {} (trajectory too short)\n", delta_text(o));
  }
  return out;
}

}  // namespace livod::eval
