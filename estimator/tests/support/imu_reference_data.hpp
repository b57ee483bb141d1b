#pragma once
// Real IMU recordings with a reference trajectory, for checking IMU propagation (header-only test
// support; see propagation_real_test.cpp for what each data set is and which frames it uses).
//   gtsam_points "continuous": imu.txt `t ax ay az wx wy wz` (100 Hz), traj.txt TUM (10 Hz)
//   EuRoC V1_01_easy:          mav0/imu0/data.csv (ADIS16448, 200 Hz), groundtruth_tum.txt
//                              (200 Hz, state_groundtruth_estimate0 converted by OpenVINS)
// Times are kept as integer ns (the files' own resolution) and turned into seconds only as
// differences.

#include <Eigen/Geometry>
#include <algorithm>
#include <charconv>
#include <cstdint>
#include <fstream>
#include <sstream>
#include <stdexcept>
#include <string>
#include <vector>

#include "core/so3.hpp"
#include "io/euroc.hpp"
#include "tests/support/data_dir.hpp"

namespace livod::estimator::test_support {

struct ReferencePose {
  std::int64_t t_ns = 0;
  Eigen::Matrix3d R_world_body = Eigen::Matrix3d::Identity();
  Eigen::Vector3d p_world_body = Eigen::Vector3d::Zero();
};

struct ImuRecord {
  std::int64_t t_ns = 0;
  Eigen::Vector3d gyro_rad_s = Eigen::Vector3d::Zero();
  Eigen::Vector3d accel_m_s2 = Eigen::Vector3d::Zero();
};

struct ImuReferenceData {
  std::vector<ImuRecord> imu;
  std::vector<ReferencePose> reference;

  // Index of the sample nearest to t (both vectors are sorted by time).
  [[nodiscard]] std::size_t imu_index(std::int64_t t_ns) const { return nearest(imu, t_ns); }
  [[nodiscard]] std::size_t reference_index(std::int64_t t_ns) const {
    return nearest(reference, t_ns);
  }

  // Reference orientation at t, interpolated on SO(3) between the neighbouring samples.
  [[nodiscard]] Eigen::Matrix3d R_world_body(std::int64_t t_ns) const {
    const auto after =
        std::upper_bound(reference.begin(), reference.end(), t_ns,
                         [](std::int64_t t, const ReferencePose& p) { return t < p.t_ns; });
    if (after == reference.begin()) return reference.front().R_world_body;
    if (after == reference.end()) return reference.back().R_world_body;
    const ReferencePose& a = *(after - 1);
    const ReferencePose& b = *after;
    const double u = static_cast<double>(t_ns - a.t_ns) / static_cast<double>(b.t_ns - a.t_ns);
    return a.R_world_body *
           so3::exp(Eigen::Vector3d(
               u * so3::log(Eigen::Matrix3d(a.R_world_body.transpose() * b.R_world_body))));
  }

 private:
  template <class T>
  static std::size_t nearest(const std::vector<T>& v, std::int64_t t_ns) {
    const auto it = std::lower_bound(v.begin(), v.end(), t_ns,
                                     [](const T& x, std::int64_t t) { return x.t_ns < t; });
    auto i = static_cast<std::size_t>(it - v.begin());
    if (i == v.size() || (i > 0 && t_ns - v[i - 1].t_ns < v[i].t_ns - t_ns)) --i;
    return i;
  }
};

inline double seconds_between(std::int64_t a_ns, std::int64_t b_ns) {
  return static_cast<double>(b_ns - a_ns) * 1e-9;
}

inline std::vector<ReferencePose> read_tum_reference(const std::filesystem::path& path) {
  std::vector<ReferencePose> out;
  for (const io::TrajectoryPose& pose : io::read_tum_trajectory(path)) {
    out.push_back(
        {pose.timestamp.ns, pose.q_world_body.normalized().toRotationMatrix(), pose.p_world_body});
  }
  return out;
}

// "1647090478.710633039" -> ns, exactly (a double holds such a stamp only to ~0.2 us).
inline std::int64_t parse_seconds_ns(const std::string& text) {
  const std::size_t dot = text.find('.');
  std::int64_t seconds = 0;
  std::from_chars(text.data(), text.data() + std::min(dot, text.size()), seconds);
  std::int64_t fraction = 0;
  if (dot != std::string::npos) {
    std::string digits = text.substr(dot + 1, 9);
    digits.resize(9, '0');
    std::from_chars(digits.data(), digits.data() + digits.size(), fraction);
  }
  return seconds * 1'000'000'000 + fraction;
}

inline ImuReferenceData load_gtsam_points_continuous() {
  ImuReferenceData data;
  const auto dir = test::data_path("imu_traj/continuous");
  std::ifstream in(dir / "imu.txt");
  std::string line;
  while (std::getline(in, line)) {
    std::istringstream fields(line);
    std::string stamp;
    ImuRecord r;
    fields >> stamp >> r.accel_m_s2.x() >> r.accel_m_s2.y() >> r.accel_m_s2.z() >>
        r.gyro_rad_s.x() >> r.gyro_rad_s.y() >> r.gyro_rad_s.z();
    if (!fields) throw std::runtime_error("imu.txt: bad line '" + line + "'");
    r.t_ns = parse_seconds_ns(stamp);
    data.imu.push_back(r);
  }
  data.reference = read_tum_reference(dir / "traj.txt");
  return data;
}

inline ImuReferenceData load_euroc_v101() {
  ImuReferenceData data;
  const auto root = test::data_path("euroc_v101");
  for (const io::EurocImuRecord& r : io::read_euroc_imu_csv(root / "mav0/imu0/data.csv")) {
    data.imu.push_back({r.timestamp.ns, r.gyro_rad_s, r.accel_m_s2});
  }
  data.reference = read_tum_reference(root / "groundtruth_tum.txt");
  return data;
}

}  // namespace livod::estimator::test_support
