// The rotation forms of an extrinsic agree with each other; the roll-pitch-yaw convention is the
// documented one; inverse and relative_to compose transforms as x_a = T_a_b * x_b.

#include <gtest/gtest.h>

#include <cmath>
#include <numbers>
#include <sstream>

#include "daemon/config/load_config.hpp"
#include "daemon/config/rotation.hpp"
#include "daemon/config/tests/config_test_support.hpp"

namespace livod::daemon {
namespace {

using test::dump;
using test::load;

constexpr double kDeg = std::numbers::pi / 180.0;

// Elementary rotations written out by hand, independent of Eigen's AngleAxis.
Eigen::Matrix3d rot_x(double a) {
  Eigen::Matrix3d R;
  R << 1, 0, 0, 0, std::cos(a), -std::sin(a), 0, std::sin(a), std::cos(a);
  return R;
}
Eigen::Matrix3d rot_y(double a) {
  Eigen::Matrix3d R;
  R << std::cos(a), 0, std::sin(a), 0, 1, 0, -std::sin(a), 0, std::cos(a);
  return R;
}
Eigen::Matrix3d rot_z(double a) {
  Eigen::Matrix3d R;
  R << std::cos(a), -std::sin(a), 0, std::sin(a), std::cos(a), 0, 0, 0, 1;
  return R;
}

TEST(ConfigRotation, RpyIsFixedAxesXThenYThenZ) {
  // Single axes: a positive yaw turns x towards y, roll turns y towards z, pitch turns z to x.
  EXPECT_TRUE((rotation_from_rpy_deg(0, 0, 90) * Eigen::Vector3d::UnitX())
                  .isApprox(Eigen::Vector3d::UnitY(), 1e-12));
  EXPECT_TRUE((rotation_from_rpy_deg(90, 0, 0) * Eigen::Vector3d::UnitY())
                  .isApprox(Eigen::Vector3d::UnitZ(), 1e-12));
  EXPECT_TRUE((rotation_from_rpy_deg(0, 90, 0) * Eigen::Vector3d::UnitZ())
                  .isApprox(Eigen::Vector3d::UnitX(), 1e-12));
  // Combined: R = Rz(yaw) Ry(pitch) Rx(roll) (ROS/URDF rpy, tf2 setRPY).
  const double roll = 30.0;
  const double pitch = -20.0;
  const double yaw = 135.0;
  const Eigen::Matrix3d expected = rot_z(yaw * kDeg) * rot_y(pitch * kDeg) * rot_x(roll * kDeg);
  EXPECT_TRUE(rotation_from_rpy_deg(roll, pitch, yaw).isApprox(expected, 1e-12));
  // ...which is not the other order.
  const Eigen::Matrix3d other = rot_x(roll * kDeg) * rot_y(pitch * kDeg) * rot_z(yaw * kDeg);
  EXPECT_FALSE(rotation_from_rpy_deg(roll, pitch, yaw).isApprox(other, 1e-3));
}

TEST(ConfigRotation, RpyRoundTrips) {
  for (const Eigen::Vector3d& rpy : {Eigen::Vector3d(30, -20, 135), Eigen::Vector3d(-170, 80, -5),
                                     Eigen::Vector3d(0, 0, 0), Eigen::Vector3d(1, 2, 3)}) {
    const Eigen::Vector3d back =
        rpy_deg_from_rotation(rotation_from_rpy_deg(rpy.x(), rpy.y(), rpy.z()));
    EXPECT_TRUE(back.isApprox(rpy, 1e-9)) << back.transpose() << " vs " << rpy.transpose();
  }
  // Gimbal lock: the angles differ but the rotation is the same.
  const Eigen::Matrix3d locked = rotation_from_rpy_deg(10, 90, 30);
  const Eigen::Vector3d back = rpy_deg_from_rotation(locked);
  EXPECT_TRUE(rotation_from_rpy_deg(back.x(), back.y(), back.z()).isApprox(locked, 1e-9));
}

TEST(ConfigRotation, QuaternionAndMatrixChecks) {
  const auto good = rotation_from_quaternion(1, 0, 0, 0);
  EXPECT_TRUE(good.ok);
  // Rounded calibration values are within tolerance and are normalised.
  const auto rounded = rotation_from_quaternion(0.7071, 0.0, 0.0, 0.7071);
  ASSERT_TRUE(rounded.ok) << rounded.message;
  EXPECT_NEAR(
      (rounded.rotation.transpose() * rounded.rotation - Eigen::Matrix3d::Identity()).norm(), 0.0,
      1e-12);
  EXPECT_TRUE(
      (rounded.rotation * Eigen::Vector3d::UnitX()).isApprox(Eigen::Vector3d::UnitY(), 1e-9));
  EXPECT_FALSE(rotation_from_quaternion(1, 1, 0, 0).ok);
  EXPECT_FALSE(rotation_from_quaternion(0, 0, 0, 0).ok);

  Eigen::Matrix3d pasted = rot_z(0.3) * rot_x(0.2);
  pasted = (pasted * 1e6).array().round() / 1e6;  // six decimals, as in a pasted file
  const auto snapped = rotation_from_matrix(pasted);
  ASSERT_TRUE(snapped.ok) << snapped.message;
  EXPECT_NEAR(snapped.rotation.determinant(), 1.0, 1e-12);
  EXPECT_TRUE(snapped.rotation.isApprox(rot_z(0.3) * rot_x(0.2), 1e-6));
  Eigen::Matrix3d scaled = 1.1 * Eigen::Matrix3d::Identity();
  EXPECT_FALSE(rotation_from_matrix(scaled).ok);
  Eigen::Matrix3d reflection = Eigen::Matrix3d::Identity();
  reflection(2, 2) = -1.0;
  const auto r = rotation_from_matrix(reflection);
  EXPECT_FALSE(r.ok);
  EXPECT_NE(r.message.find("reflection"), std::string::npos);
}

std::string sensor_with_extrinsic(const std::string& name, const std::string& extrinsic) {
  return "  - {name: " + name +
         ", driver: velodyne, model: VLP-16, enabled: false, source: {udp: {}}, extrinsic: " +
         extrinsic + "}\n";
}

// The same pose in all five spellings gives the same T_body_sensor.
TEST(ConfigRotation, AllFormsAgree) {
  const double roll = 12.0;
  const double pitch = -35.0;
  const double yaw = 160.0;
  const Eigen::Matrix3d R = rot_z(yaw * kDeg) * rot_y(pitch * kDeg) * rot_x(roll * kDeg);
  const Eigen::Quaterniond q(R);
  const Eigen::Vector3d t(0.25, -0.5, 1.5);
  auto list = [](std::initializer_list<double> values) {
    std::ostringstream out;
    out.precision(17);
    out << '[';
    bool first = true;
    for (double v : values) {
      out << (first ? "" : ", ") << v;
      first = false;
    }
    out << ']';
    return out.str();
  };
  const std::string translation = "translation: " + list({t.x(), t.y(), t.z()});
  const std::string matrix =
      list({R(0, 0), R(0, 1), R(0, 2), R(1, 0), R(1, 1), R(1, 2), R(2, 0), R(2, 1), R(2, 2)});
  const std::string transform = list({R(0, 0), R(0, 1), R(0, 2), t.x(), R(1, 0), R(1, 1), R(1, 2),
                                      t.y(), R(2, 0), R(2, 1), R(2, 2), t.z(), 0, 0, 0, 1});
  std::string yaml = test::minimal_config();
  yaml += sensor_with_extrinsic(
      "rpy", "{" + translation + ", rotation: {rpy_deg: " + list({roll, pitch, yaw}) + "}}");
  yaml += sensor_with_extrinsic("wxyz", "{" + translation + ", rotation: {quaternion_wxyz: " +
                                            list({q.w(), q.x(), q.y(), q.z()}) + "}}");
  yaml += sensor_with_extrinsic("xyzw", "{" + translation + ", rotation: {quaternion_xyzw: " +
                                            list({q.x(), q.y(), q.z(), q.w()}) + "}}");
  yaml +=
      sensor_with_extrinsic("matrix", "{" + translation + ", rotation: {matrix: " + matrix + "}}");
  yaml += sensor_with_extrinsic("transform", "{transform: " + transform + "}");
  const auto result = load(yaml);
  ASSERT_TRUE(result.problems.empty()) << dump(result);
  for (const char* name : {"rpy", "wxyz", "xyzw", "matrix", "transform"}) {
    const SensorConfig* s = result.config.find_sensor(name);
    ASSERT_NE(s, nullptr);
    EXPECT_TRUE(s->T_body_sensor.linear().isApprox(R, 1e-12)) << name;
    EXPECT_TRUE(s->T_body_sensor.translation().isApprox(t, 1e-12)) << name;
    // x_body = R * x_sensor + t
    const Eigen::Vector3d x_sensor(1.0, 2.0, 3.0);
    EXPECT_TRUE((s->T_body_sensor * x_sensor).isApprox(R * x_sensor + t, 1e-12)) << name;
  }
}

TEST(ConfigRotation, InverseAndRelativeToCompose) {
  // lidar: T_body_lidar from the minimal config (t = [0.1, 0, 0.2], R = I).
  // cam_a: T_lidar_cam given directly, relative to the lidar.
  // cam_b: the same pose given as T_cam_lidar with inverse: true (FAST-LIVO2's Rcl/Pcl style).
  const Eigen::Matrix3d R_lidar_cam = rot_z(-90 * kDeg) * rot_x(-90 * kDeg);
  const Eigen::Vector3d t_lidar_cam(0.05, -0.02, 0.03);
  Eigen::Isometry3d T_lidar_cam = Eigen::Isometry3d::Identity();
  T_lidar_cam.linear() = R_lidar_cam;
  T_lidar_cam.translation() = t_lidar_cam;
  const Eigen::Isometry3d T_cam_lidar = T_lidar_cam.inverse();
  auto vec = [](const Eigen::Vector3d& v) {
    std::ostringstream out;
    out.precision(17);
    out << '[' << v.x() << ", " << v.y() << ", " << v.z() << ']';
    return out.str();
  };
  const Eigen::Quaterniond q_cl(T_cam_lidar.linear());
  std::ostringstream q_text;
  q_text.precision(17);
  q_text << '[' << q_cl.w() << ", " << q_cl.x() << ", " << q_cl.y() << ", " << q_cl.z() << ']';
  const std::string yaml =
      test::minimal_config() +
      sensor_with_extrinsic("cam_a", "{relative_to: lidar, translation: " + vec(t_lidar_cam) +
                                         ", rotation: {rpy_deg: [-90, 0, -90]}}") +
      sensor_with_extrinsic("cam_b", "{relative_to: lidar, inverse: true, translation: " +
                                         vec(T_cam_lidar.translation()) +
                                         ", rotation: {quaternion_wxyz: " + q_text.str() + "}}") +
      sensor_with_extrinsic("chained",
                            "{relative_to: cam_b, translation: [0, 0, 1], "
                            "rotation: {rpy_deg: [0, 0, 0]}}");
  const auto result = load(yaml);
  ASSERT_TRUE(result.problems.empty()) << dump(result);
  const Eigen::Isometry3d T_body_lidar = result.config.find_sensor("lidar")->T_body_sensor;
  const Eigen::Isometry3d expected = T_body_lidar * T_lidar_cam;
  const auto& a = result.config.find_sensor("cam_a")->T_body_sensor;
  const auto& b = result.config.find_sensor("cam_b")->T_body_sensor;
  EXPECT_TRUE(a.matrix().isApprox(expected.matrix(), 1e-12)) << a.matrix() << "\n"
                                                             << expected.matrix();
  EXPECT_TRUE(b.matrix().isApprox(expected.matrix(), 1e-12)) << b.matrix();
  // The camera's optical axis (z) looks along the LiDAR's x axis.
  EXPECT_TRUE((a.linear() * Eigen::Vector3d::UnitZ()).isApprox(Eigen::Vector3d::UnitX(), 1e-12));
  // A point 1 m in front of cam_b, expressed in the body frame.
  const auto& chained = result.config.find_sensor("chained")->T_body_sensor;
  EXPECT_TRUE(chained.translation().isApprox(b * Eigen::Vector3d(0, 0, 1), 1e-12));
}

TEST(ConfigRotation, BadRotationsAreReported) {
  const std::string base = test::minimal_config();
  const auto not_unit = load(
      base + sensor_with_extrinsic(
                 "q", "{translation: [0, 0, 0], rotation: {quaternion_wxyz: [1, 0.1, 0, 0]}}"));
  ASSERT_EQ(not_unit.problems.size(), 1u) << dump(not_unit);
  EXPECT_EQ(not_unit.problems[0].path, "sensors[2].extrinsic.rotation.quaternion_wxyz");
  EXPECT_NE(not_unit.problems[0].message.find("quaternion norm is 1.00499"), std::string::npos)
      << not_unit.problems[0].message;
  const auto two_forms =
      load(base + sensor_with_extrinsic("q",
                                        "{translation: [0, 0, 0], rotation: {rpy_deg: [0, 0, 0], "
                                        "matrix: [1, 0, 0, 0, 1, 0, 0, 0, 1]}}"));
  ASSERT_EQ(two_forms.problems.size(), 1u) << dump(two_forms);
  EXPECT_EQ(two_forms.problems[0].kind, ProblemKind::inconsistent);
  const auto bad_row =
      load(base + sensor_with_extrinsic(
                      "t", "{transform: [1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1, 0, 0, 0, 1, 1]}"));
  ASSERT_EQ(bad_row.problems.size(), 1u) << dump(bad_row);
  EXPECT_EQ(bad_row.problems[0].path, "sensors[2].extrinsic.transform");
  const auto millimetres =
      load(base + sensor_with_extrinsic("mm",
                                        "{translation: [6.253, -11.775, 7.645], "
                                        "rotation: {rpy_deg: [0, 0, 0]}}"));
  ASSERT_EQ(millimetres.problems.size(), 1u) << dump(millimetres);
  EXPECT_EQ(millimetres.problems[0].severity, Severity::warning);
}

}  // namespace
}  // namespace livod::daemon
