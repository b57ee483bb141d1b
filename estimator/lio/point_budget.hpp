#pragma once
// The downsampling cell of each scan, chosen so that about `budget` points go into the update
// (LioParams::point_budget): the per-frame cost of association, the update and the map insertion
// grows with that count, the number of points a scan brings does not matter to it. A 128-beam
// Ouster outdoors and a Livox in a small room then cost about the same per scan, and the same
// sensor keeps its detail indoors (small cells) and its speed outdoors (large cells) without being
// told where it is.
//
// Surface points per scan fall as 1 / cell^2, so the next cell is the last one scaled by
// sqrt(points / budget), within [min_cell, max_cell]. A scan that brings far more points than the
// last one (entering a street from a building) is downsampled once more with the corrected cell,
// so no frame runs with several times the budget. Depends only on the data: replays stay
// deterministic.
//
// The cell moves on a ladder, min_cell x 2^(k/8) (capped at max_cell), not continuously: the same
// recording delivered by another container (bag, pcap) or cut a packet apart brings a few points
// more or fewer per scan, and a cell that followed the count continuously would differ in the last
// digits, and so would every scan's selection after it. On the ladder a count that differs by a few
// points gives the same step unless it sits right at a step's edge.

#include <cstddef>

namespace livod::estimator {

class PointBudget {
 public:
  PointBudget(int budget, double min_cell, double max_cell);

  // The cell to downsample the next scan with.
  [[nodiscard]] double cell() const { return cell_; }
  // A scan downsampled with cell() kept `points`: adapts cell() and returns true when the scan
  // overshot so far (more than kRedoFactor x budget with room to grow) that it should be
  // downsampled again with the new cell().
  bool observe(std::size_t points);
  // Several LiDARs: an update kept `points` over `fraction` of the span the budget is for (its
  // time over a scan period / n). The count is scaled to that span; an update shorter than
  // kMinFraction is not counted (scans that end together leave one of a few points, which would
  // shrink the cell for the next update's whole scans).
  void observe_part(std::size_t points, double fraction);

  [[nodiscard]] int budget() const { return budget_; }

  static constexpr double kRedoFactor = 1.5;
  static constexpr double kMinFraction = 0.25;
  // Steps of the cell ladder per doubling of the cell.
  static constexpr int kStepsPerOctave = 8;

 private:
  int budget_;
  double min_cell_;
  double max_cell_;
  int max_step_;
  int step_ = 0;  // cell() is min_cell x 2^(step_ / kStepsPerOctave)
  double cell_;
};

}  // namespace livod::estimator
