#include "estimator/vio/recent_sweep.hpp"

namespace livod::estimator::vio {

void RecentSweep::append(const std::vector<CovPoint>& points,
                         const std::vector<Eigen::Vector3d>& normals,
                         std::vector<CovPoint>& to_points,
                         std::vector<Eigen::Vector3d>& to_normals) {
  to_points.insert(to_points.end(), points.begin(), points.end());
  if (normals.size() == points.size()) {
    to_normals.insert(to_normals.end(), normals.begin(), normals.end());
  } else {
    to_normals.resize(to_points.size(), Eigen::Vector3d::Zero());
  }
}

RecentSweep::View RecentSweep::add(MappedTime t_begin, MappedTime t_end, Nanoseconds period,
                                   const std::vector<CovPoint>& points,
                                   const std::vector<Eigen::Vector3d>& normals) {
  const Nanoseconds reach = period + period / 10;
  while (!parts_.empty() && t_end - parts_.front().t_begin > reach) parts_.pop_front();
  View view{&points, &normals};
  if (!parts_.empty()) {
    points_.clear();
    normals_.clear();
    for (const Part& part : parts_) append(part.points, part.normals, points_, normals_);
    append(points, normals, points_, normals_);
    view = View{&points_, &normals_};
  }
  // Only a group shorter than a scan period can join a later one within the reach.
  if (t_end - t_begin < period - period / 10) {
    Part part;
    part.t_begin = t_begin;
    append(points, normals, part.points, part.normals);
    parts_.push_back(std::move(part));
  } else {
    parts_.clear();
  }
  return view;
}

std::size_t RecentSweep::stored_points() const {
  std::size_t n = 0;
  for (const Part& part : parts_) n += part.points.size();
  return n;
}

}  // namespace livod::estimator::vio
