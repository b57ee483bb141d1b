#include "tools/eval/evaluate.hpp"

#include <fmt/format.h>

#include <cmath>
#include <numbers>
#include <string>

#include "core/error.hpp"
#include "core/so3.hpp"

namespace livod::eval {
namespace {

constexpr std::size_t kMinAlignmentPairs = 3;
constexpr std::size_t kFewAlignmentPairs = 10;

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

// Drops poses whose stamp repeats the previous one (keeps the first): a pose written twice would
// count twice in ATE and make zero-length RPE pairs that pull the RPE statistics down.
Trajectory without_repeated_stamps(const Trajectory& t, std::size_t& dropped) {
  dropped = 0;
  if (t.stamps_s.size() != t.poses.size()) return t;  // KITTI without times: no stamps
  std::vector<std::size_t> keep;
  keep.reserve(t.size());
  for (std::size_t i = 0; i < t.size(); ++i) {
    if (i > 0 && t.stamps_s[i] == t.stamps_s[i - 1]) {
      ++dropped;
    } else {
      keep.push_back(i);
    }
  }
  return dropped == 0 ? t : t.subset(keep);
}

}  // namespace

EvalResult evaluate(const Trajectory& gt_read, const Trajectory& est_read,
                    const EvalOptions& options) {
  if (gt_read.empty()) throw Error("the ground truth has no poses");
  if (est_read.empty()) throw Error("the estimate has no poses");
  EvalResult r;
  r.gt_poses_read = gt_read.size();
  r.est_poses_read = est_read.size();
  std::size_t gt_repeats = 0;
  std::size_t est_repeats = 0;
  const Trajectory gt = without_repeated_stamps(gt_read, gt_repeats);
  const Trajectory est = without_repeated_stamps(est_read, est_repeats);
  for (const auto& [name, n] : {std::pair{"ground truth", gt_repeats}, {"estimate", est_repeats}}) {
    if (n > 0) {
      r.warnings.push_back(fmt::format(
          "the {} repeats the timestamp of the previous pose {} time(s): those poses were "
          "dropped (the first of each stamp kept)",
          name, n));
    }
  }

  // KITTI pairs pose i with pose i even with a times file: both files index the same frames.
  const bool by_time = options.format != TrajectoryFormat::kKitti;
  const Association a =
      by_time ? associate_by_time(gt, est, options.max_time_diff_s, options.time_offset_s)
              : associate_by_index(gt, est);
  r.associated_by_time = by_time;
  r.gt = gt.subset(a.gt_index);
  const Trajectory est_assoc = est.subset(a.est_index);

  // An alignment needs three non-collinear positions to fix a rotation; fewer pairs would give an
  // arbitrary one and an ATE near zero.
  if (options.alignment != Alignment::kNone && r.gt.size() < kMinAlignmentPairs) {
    throw Error("only " + std::to_string(r.gt.size()) + " associated pose pair(s): " +
                std::string(to_string(options.alignment)) + " alignment needs at least " +
                std::to_string(kMinAlignmentPairs) + " (or --align none)");
  }
  if (options.alignment != Alignment::kNone && r.gt.size() < kFewAlignmentPairs) {
    r.warnings.push_back(
        fmt::format("the {} alignment rests on only {} pose pairs: it is poorly determined",
                    to_string(options.alignment), r.gt.size()));
  }
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
  const bool finite = std::isfinite(r.ape.rmse) && std::isfinite(r.alignment.scale) &&
                      (!r.rpe_translation || (std::isfinite(r.rpe_translation->rmse) &&
                                              std::isfinite(r.rpe_rotation->rmse)));
  if (!finite) throw Error("the errors are not finite numbers: check the trajectories' values");
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
  for (const auto& w : r.warnings) out += "warning      " + w + "\n";
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
