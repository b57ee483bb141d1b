#include "tools/eval/trajectory.hpp"

namespace livod::eval {

double Trajectory::path_length() const {
  double length = 0.0;
  for (std::size_t i = 1; i < poses.size(); ++i) {
    length += (poses[i].translation - poses[i - 1].translation).norm();
  }
  return length;
}

Trajectory Trajectory::subset(const std::vector<std::size_t>& indices) const {
  Trajectory out;
  out.poses.reserve(indices.size());
  if (has_stamps()) out.stamps_s.reserve(indices.size());
  for (std::size_t i : indices) {
    out.poses.push_back(poses.at(i));
    if (has_stamps()) out.stamps_s.push_back(stamps_s.at(i));
  }
  return out;
}

}  // namespace livod::eval
