#include "estimator/lio/point_budget.hpp"

#include <algorithm>
#include <cmath>

namespace livod::estimator {

PointBudget::PointBudget(int budget, double min_cell, double max_cell)
    : budget_(std::max(budget, 1)),
      min_cell_(min_cell),
      max_cell_(std::max(min_cell, max_cell)),
      // The first step at or above max_cell (which is the ladder's top: cell() is capped there).
      max_step_(min_cell > 0.0 ? static_cast<int>(std::ceil(
                                     kStepsPerOctave * std::log2(max_cell_ / min_cell_) - 1e-9))
                               : 0),
      cell_(min_cell) {}

bool PointBudget::observe(std::size_t points) {
  const double ratio = static_cast<double>(points) / static_cast<double>(budget_);
  const int previous = step_;
  // Within 15 % of the budget the cell stays put: no hunting between neighbouring sizes.
  if (ratio > 1.15 || ratio < 0.85) {
    // Surface points fall as 1 / cell^2: the cell that fits is cell x sqrt(ratio), i.e.
    // 0.5 log2(ratio) octaves away, rounded to the ladder.
    const double steps = 0.5 * kStepsPerOctave * std::log2(std::max(ratio, 1e-3));
    step_ = std::clamp(step_ + static_cast<int>(std::lround(steps)), 0, max_step_);
    cell_ =
        std::min(max_cell_, min_cell_ * std::exp2(static_cast<double>(step_) / kStepsPerOctave));
  }
  return ratio > kRedoFactor && step_ > previous;
}

void PointBudget::observe_part(std::size_t points, double fraction) {
  if (!(fraction >= kMinFraction)) return;
  observe(static_cast<std::size_t>(std::lround(static_cast<double>(points) / fraction)));
}

}  // namespace livod::estimator
