#include "tools/eval/alignment.hpp"

#include <Eigen/LU>
#include <Eigen/SVD>
#include <string>

#include "core/error.hpp"

namespace livod::eval {

std::optional<Alignment> parse_alignment(std::string_view name) {
  if (name == "none") return Alignment::kNone;
  if (name == "se3") return Alignment::kSe3;
  if (name == "sim3") return Alignment::kSim3;
  return std::nullopt;
}

std::string_view to_string(Alignment alignment) {
  switch (alignment) {
    case Alignment::kNone:
      return "none";
    case Alignment::kSe3:
      return "se3";
    case Alignment::kSim3:
      return "sim3";
  }
  return "?";
}

Similarity3 umeyama(const std::vector<Eigen::Vector3d>& est, const std::vector<Eigen::Vector3d>& gt,
                    bool with_scale) {
  if (est.size() != gt.size()) throw Error("umeyama: point sets differ in size");
  if (est.size() < 2) throw Error("umeyama: need at least 2 associated poses to align");
  const double n = static_cast<double>(est.size());
  Eigen::Vector3d mean_est = Eigen::Vector3d::Zero();
  Eigen::Vector3d mean_gt = Eigen::Vector3d::Zero();
  for (std::size_t i = 0; i < est.size(); ++i) {
    mean_est += est[i];
    mean_gt += gt[i];
  }
  mean_est /= n;
  mean_gt /= n;

  // Σ_xy = 1/n Σ (gt_i − μ_gt)(est_i − μ_est)ᵀ and σ²_est = 1/n Σ |est_i − μ_est|².
  Eigen::Matrix3d cov = Eigen::Matrix3d::Zero();
  double var_est = 0.0;
  for (std::size_t i = 0; i < est.size(); ++i) {
    const Eigen::Vector3d de = est[i] - mean_est;
    cov += (gt[i] - mean_gt) * de.transpose();
    var_est += de.squaredNorm();
  }
  cov /= n;
  var_est /= n;
  if (!(var_est > 0.0)) throw Error("umeyama: the estimate's positions are all identical");

  const Eigen::JacobiSVD<Eigen::Matrix3d> svd(cov, Eigen::ComputeFullU | Eigen::ComputeFullV);
  // S flips the weakest axis when U·Vᵀ would be a reflection (Umeyama eq. 39/43).
  Eigen::Vector3d s(1.0, 1.0, 1.0);
  if (svd.matrixU().determinant() * svd.matrixV().determinant() < 0.0) s(2) = -1.0;

  Similarity3 sim;
  sim.rotation = svd.matrixU() * s.asDiagonal() * svd.matrixV().transpose();
  sim.scale = with_scale ? svd.singularValues().dot(s) / var_est : 1.0;
  sim.translation = mean_gt - sim.scale * sim.rotation * mean_est;
  return sim;
}

Similarity3 align(const Trajectory& gt, const Trajectory& est, Alignment alignment) {
  if (alignment == Alignment::kNone) return {};
  std::vector<Eigen::Vector3d> p_est;
  std::vector<Eigen::Vector3d> p_gt;
  p_est.reserve(est.size());
  p_gt.reserve(gt.size());
  for (const RigidTransform3d& t : est.poses) p_est.push_back(t.translation);
  for (const RigidTransform3d& t : gt.poses) p_gt.push_back(t.translation);
  return umeyama(p_est, p_gt, alignment == Alignment::kSim3);
}

Trajectory transformed(const Trajectory& traj, const Similarity3& sim) {
  Trajectory out;
  out.stamps_s = traj.stamps_s;
  out.poses.reserve(traj.size());
  for (const RigidTransform3d& t : traj.poses) out.poses.push_back(sim.apply(t));
  return out;
}

}  // namespace livod::eval
