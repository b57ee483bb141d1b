#include "estimator/lio/point_budget.hpp"

#include <algorithm>
#include <cmath>

namespace livod::estimator {

PointBudget::PointBudget(int budget, double min_cell, double max_cell)
    : budget_(std::max(budget, 1)),
      min_cell_(min_cell),
      max_cell_(std::max(min_cell, max_cell)),
      cell_(min_cell) {}

bool PointBudget::observe(std::size_t points) {
  const double ratio = static_cast<double>(points) / static_cast<double>(budget_);
  const double previous = cell_;
  // Within 15 % of the budget the cell stays put: no hunting between neighbouring sizes.
  if (ratio > 1.15 || ratio < 0.85) {
    cell_ = std::clamp(cell_ * std::sqrt(std::max(ratio, 1e-3)), min_cell_, max_cell_);
  }
  return ratio > kRedoFactor && cell_ > previous;
}

}  // namespace livod::estimator
