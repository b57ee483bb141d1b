#include "tools/eval/metrics.hpp"

#include <algorithm>
#include <cmath>
#include <numbers>
#include <string>

#include "core/error.hpp"
#include "core/so3.hpp"

namespace livod::eval {

ErrorStatistics compute_statistics(std::span<const double> errors) {
  if (errors.empty()) throw Error("no errors to summarise");
  ErrorStatistics s;
  s.count = errors.size();
  const double n = static_cast<double>(errors.size());
  double sum = 0.0;
  s.min = errors.front();
  s.max = errors.front();
  for (double e : errors) {
    sum += e;
    s.sse += e * e;
    s.min = std::min(s.min, e);
    s.max = std::max(s.max, e);
  }
  s.mean = sum / n;
  s.rmse = std::sqrt(s.sse / n);
  double var = 0.0;
  for (double e : errors) var += (e - s.mean) * (e - s.mean);
  s.std = std::sqrt(var / n);
  std::vector<double> sorted(errors.begin(), errors.end());
  const std::size_t mid = sorted.size() / 2;
  std::nth_element(sorted.begin(), sorted.begin() + static_cast<std::ptrdiff_t>(mid), sorted.end());
  s.median = sorted[mid];
  if (sorted.size() % 2 == 0) {
    // Mean of the two middle values: the lower one is the largest of the lower half.
    const double lower =
        *std::max_element(sorted.begin(), sorted.begin() + static_cast<std::ptrdiff_t>(mid));
    s.median = 0.5 * (lower + s.median);
  }
  return s;
}

std::vector<double> absolute_translation_errors(const Trajectory& gt, const Trajectory& est) {
  if (gt.size() != est.size()) throw Error("APE needs associated trajectories of equal length");
  std::vector<double> e(gt.size());
  for (std::size_t i = 0; i < gt.size(); ++i) {
    e[i] = (est.poses[i].translation - gt.poses[i].translation).norm();
  }
  return e;
}

std::optional<DeltaUnit> parse_delta_unit(std::string_view name) {
  if (name == "m") return DeltaUnit::kMeters;
  if (name == "s") return DeltaUnit::kSeconds;
  if (name == "frames" || name == "f") return DeltaUnit::kFrames;
  return std::nullopt;
}

std::string_view to_string(DeltaUnit unit) {
  switch (unit) {
    case DeltaUnit::kMeters:
      return "m";
    case DeltaUnit::kSeconds:
      return "s";
    case DeltaUnit::kFrames:
      return "frames";
  }
  return "?";
}

std::vector<IndexPair> select_rpe_pairs(const Trajectory& traj, double delta, DeltaUnit unit) {
  if (!(delta > 0.0) || !std::isfinite(delta)) throw Error("RPE delta must be positive");
  std::vector<std::size_t> ids;
  switch (unit) {
    case DeltaUnit::kFrames: {
      if (delta != std::floor(delta)) throw Error("RPE delta in frames must be an integer");
      const auto step = static_cast<std::size_t>(delta);
      for (std::size_t i = 0; i < traj.size(); i += step) ids.push_back(i);
      break;
    }
    case DeltaUnit::kMeters: {
      double path = 0.0;
      for (std::size_t i = 1; i < traj.size(); ++i) {
        path += (traj.poses[i].translation - traj.poses[i - 1].translation).norm();
        if (path >= delta) {
          ids.push_back(i);
          path = 0.0;
        }
      }
      break;
    }
    case DeltaUnit::kSeconds: {
      if (!traj.has_stamps()) throw Error("RPE delta in seconds needs timestamps");
      if (traj.empty()) break;
      ids.push_back(0);
      for (std::size_t i = 1; i < traj.size(); ++i) {
        if (traj.stamps_s[i] - traj.stamps_s[ids.back()] >= delta) ids.push_back(i);
      }
      break;
    }
  }
  std::vector<IndexPair> pairs;
  for (std::size_t k = 1; k < ids.size(); ++k) pairs.emplace_back(ids[k - 1], ids[k]);
  return pairs;
}

RelativeErrors relative_pose_errors(const Trajectory& gt, const Trajectory& est,
                                    const std::vector<IndexPair>& pairs) {
  if (gt.size() != est.size()) throw Error("RPE needs associated trajectories of equal length");
  RelativeErrors r;
  r.pairs = pairs;
  r.translation_m.reserve(pairs.size());
  r.rotation_deg.reserve(pairs.size());
  for (const auto& [i, j] : pairs) {
    const RigidTransform3d gt_rel = gt.poses[i].inverse() * gt.poses[j];
    const RigidTransform3d est_rel = est.poses[i].inverse() * est.poses[j];
    const RigidTransform3d e = gt_rel.inverse() * est_rel;
    r.translation_m.push_back(e.translation.norm());
    r.rotation_deg.push_back(so3::angle(e.rotation) * 180.0 / std::numbers::pi);
  }
  return r;
}

}  // namespace livod::eval
