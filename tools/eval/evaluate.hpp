#pragma once
// `livod eval` as a library: read ground truth and estimate, associate, align, and compute ATE
// and RPE, reproducing evo's numbers (evo_ape / evo_rpe) for the same options.

#include <cstddef>
#include <filesystem>
#include <optional>
#include <string>
#include <vector>

#include "tools/eval/alignment.hpp"
#include "tools/eval/association.hpp"
#include "tools/eval/metrics.hpp"
#include "tools/eval/trajectory.hpp"
#include "tools/eval/trajectory_io.hpp"

namespace livod::eval {

struct EvalOptions {
  TrajectoryFormat format = TrajectoryFormat::kTum;
  std::optional<std::filesystem::path> kitti_times;  // stamps both KITTI files (for plots/RPE s)
  Alignment alignment = Alignment::kSe3;
  double max_time_diff_s = 0.01;  // evo's --t_max_diff default
  double time_offset_s = 0.0;     // added to the estimate's stamps (evo's --t_offset)
  double rpe_delta = 1.0;
  DeltaUnit rpe_unit = DeltaUnit::kFrames;  // evo's default: 1 frame
};

struct EvalResult {
  std::size_t gt_poses_read = 0;
  std::size_t est_poses_read = 0;
  bool associated_by_time = false;
  Trajectory gt;           // associated ground truth
  Trajectory est_aligned;  // associated estimate, alignment applied
  Similarity3 alignment;   // x_gt = s·R·x_est + t
  std::vector<double> ape_m;
  ErrorStatistics ape;
  RelativeErrors rpe;
  std::optional<ErrorStatistics> rpe_translation;  // empty when delta yields no pair
  std::optional<ErrorStatistics> rpe_rotation;
  // What the user must know about these numbers (repeated stamps dropped, a weak alignment).
  std::vector<std::string> warnings;
};

// Ground truth and estimate already read. Throws livod::Error when association fails.
EvalResult evaluate(const Trajectory& gt, const Trajectory& est, const EvalOptions& options);

// Reads both files in options.format (EuRoC: ground truth csv, estimate TUM) and evaluates.
EvalResult evaluate_files(const std::filesystem::path& est_path,
                          const std::filesystem::path& gt_path, const EvalOptions& options);

// The text table printed by `livod eval`; its ATE line reads
// "ATE  RMSE <m> m  mean ... median ... std ... min ... max ... (<N> poses)".
std::string format_report(const EvalResult& result, const EvalOptions& options);

}  // namespace livod::eval
