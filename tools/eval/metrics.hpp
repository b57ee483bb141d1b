#pragma once
// Error metrics over associated trajectories (same length, pose i ↔ pose i).
//
// ATE / APE (translation part): e_i = |p_est,i − p_gt,i| after alignment.
// RPE (TUM RGB-D benchmark, Sturm et al. 2012): for an index pair (i, j)
//   E = (Q_i⁻¹·Q_j)⁻¹ · (P_i⁻¹·P_j),  Q ground truth, P estimate;
// the translation error is |t(E)| (m), the rotation error the angle of R(E) (degrees).
// Pairs are consecutive, non-overlapping sub-sequences of length delta chosen on the estimate
// (evo's default, all_pairs = False):
//   frames:  0, d, 2d, ...
//   metres:  walk the path; an index is taken each time the path accumulated since the last one
//            reaches delta (the first index is the first whose path from pose 0 reaches delta)
//   seconds: 0, then each first index at least delta seconds after the previous one.

#include <cstddef>
#include <optional>
#include <span>
#include <string_view>
#include <utility>
#include <vector>

#include "tools/eval/trajectory.hpp"

namespace livod::eval {

struct ErrorStatistics {
  std::size_t count = 0;
  double rmse = 0.0;
  double mean = 0.0;
  double median = 0.0;
  double std = 0.0;  // population standard deviation (numpy's default, as evo)
  double min = 0.0;
  double max = 0.0;
  double sse = 0.0;  // sum of squared errors
};

// Throws livod::Error on an empty input.
ErrorStatistics compute_statistics(std::span<const double> errors);

// Translation error per associated pose, metres.
std::vector<double> absolute_translation_errors(const Trajectory& gt, const Trajectory& est);

enum class DeltaUnit { kMeters, kSeconds, kFrames };

std::optional<DeltaUnit> parse_delta_unit(std::string_view name);  // "m" | "s" | "frames"
std::string_view to_string(DeltaUnit unit);

using IndexPair = std::pair<std::size_t, std::size_t>;

// Throws livod::Error for a non-positive delta, a non-integer frame delta, or seconds without
// stamps. An empty result is not an error here (the caller reports it).
std::vector<IndexPair> select_rpe_pairs(const Trajectory& traj, double delta, DeltaUnit unit);

struct RelativeErrors {
  std::vector<IndexPair> pairs;
  std::vector<double> translation_m;
  std::vector<double> rotation_deg;
};

RelativeErrors relative_pose_errors(const Trajectory& gt, const Trajectory& est,
                                    const std::vector<IndexPair>& pairs);

}  // namespace livod::eval
