#pragma once
// PNG summary of an evaluation: left, the trajectories seen from above (ground truth and the
// aligned estimate, on the two axes along which the ground truth extends most, equal scale);
// right, the ATE translation error over time (or pose index when there are no stamps) with its
// RMSE and mean. OpenCV stays inside plot.cpp.

#include <filesystem>
#include <string>

#include "tools/eval/evaluate.hpp"

namespace livod::eval {

// Throws livod::Error when the image cannot be encoded or written.
void write_plot(const std::filesystem::path& png_path, const EvalResult& result,
                const std::string& title);

}  // namespace livod::eval
