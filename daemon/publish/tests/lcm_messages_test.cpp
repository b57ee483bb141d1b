// Records -> LCM messages (daemon/publish/lcm_messages.hpp, pose_from_estimator.hpp,
// health_from_sources.hpp), checked field by field on the generated types.

#include "daemon/publish/lcm_messages.hpp"

#include <gtest/gtest.h>

#include <Eigen/Cholesky>
#include <Eigen/Geometry>
#include <bit>
#include <cmath>
#include <limits>
#include <random>
#include <set>
#include <vector>

#include "core/so3.hpp"
#include "daemon/publish/health_from_sources.hpp"
#include "daemon/publish/pose_from_estimator.hpp"

namespace livod::daemon::publish {
namespace {

constexpr std::int64_t kUnixOffset = 1'700'000'000'000'000'000;  // 2023-11-14, in ns

Eigen::Matrix3d rot(double angle, const Eigen::Vector3d& axis) {
  return Eigen::AngleAxisd(angle, axis.normalized()).toRotationMatrix();
}

PoseRecord sample_pose() {
  PoseRecord p;
  p.t = MappedTime(123'456'789'012);
  p.filter_t = MappedTime(123'400'000'000);
  p.has_filter_update = true;
  p.source = PoseSource::kImuPropagated;
  p.status = PoseStatus::kDegenerate;
  p.R_world_body = rot(0.7, {1.0, -2.0, 0.5});
  p.p_world_body = {1.5, -2.25, 3.125};
  p.v_world = {0.5, 0.25, -0.125};
  p.omega_body = {0.01, -0.02, 0.03};
  p.accel_world = {0.1, 0.2, -0.3};
  for (int r = 0; r < 6; ++r) {
    for (int c = 0; c < 6; ++c) p.covariance(r, c) = 1e-3 * (10 * r + c + 1);
  }
  return p;
}

template <class Message>
std::vector<std::uint8_t> encoded(const Message& m) {
  std::vector<std::uint8_t> bytes(static_cast<std::size_t>(m.getEncodedSize()));
  EXPECT_EQ(m.encode(bytes.data(), 0, static_cast<int>(bytes.size())),
            static_cast<int>(bytes.size()));
  return bytes;
}

// Decodes what was encoded and checks that re-encoding gives the same bytes (the generated types
// have no operator==).
template <class Message>
void expect_round_trip(const Message& m) {
  const auto bytes = encoded(m);
  Message back;
  ASSERT_EQ(back.decode(bytes.data(), 0, static_cast<int>(bytes.size())),
            static_cast<int>(bytes.size()));
  EXPECT_EQ(encoded(back), bytes);
}

TEST(LcmMessages, UtimeRoundsTowardsMinusInfinity) {
  EXPECT_EQ(utime_of(0), 0);
  EXPECT_EQ(utime_of(999), 0);
  EXPECT_EQ(utime_of(1000), 1);
  EXPECT_EQ(utime_of(1999), 1);
  EXPECT_EQ(utime_of(-1), -1);
  EXPECT_EQ(utime_of(-1000), -1);
  EXPECT_EQ(utime_of(-1001), -2);
  EXPECT_EQ(utime_of(kUnixOffset + 123'456'789), kUnixOffset / 1000 + 123'456);
}

TEST(LcmMessages, PoseCarriesEveryField) {
  const PoseRecord p = sample_pose();
  const Frames frames{"map", "os1.imu"};
  const ::livod::pose_t m = to_lcm_pose(p, frames, TimeBase{kUnixOffset}, 42);

  EXPECT_EQ(m.time_ns, kUnixOffset + 123'456'789'012);
  EXPECT_EQ(m.utime, (kUnixOffset + 123'456'789'012) / 1000);
  EXPECT_EQ(m.mapped_time_ns, 123'456'789'012);
  EXPECT_EQ(m.filter_time_ns, kUnixOffset + 123'400'000'000);
  EXPECT_EQ(m.sequence, 42);
  EXPECT_EQ(m.source, ::livod::pose_t::SOURCE_IMU_PROPAGATED);
  EXPECT_EQ(m.status, ::livod::pose_t::STATUS_DEGENERATE);
  EXPECT_EQ(m.world_frame, "map");
  EXPECT_EQ(m.body_frame, "os1.imu");
  for (int i = 0; i < 3; ++i) {
    EXPECT_EQ(m.position[i], p.p_world_body[i]);
    EXPECT_EQ(m.velocity[i], p.v_world[i]);
    EXPECT_EQ(m.angular_velocity[i], p.omega_body[i]);
    EXPECT_EQ(m.acceleration[i], p.accel_world[i]);
  }
  const Eigen::Quaterniond q(m.orientation[0], m.orientation[1], m.orientation[2],
                             m.orientation[3]);
  EXPECT_NEAR(q.norm(), 1.0, 1e-15);
  EXPECT_TRUE(q.toRotationMatrix().isApprox(p.R_world_body, 1e-14));
  for (int r = 0; r < 6; ++r) {
    for (int c = 0; c < 6; ++c) EXPECT_EQ(m.covariance[r][c], p.covariance(r, c)) << r << c;
  }
  expect_round_trip(m);
}

TEST(LcmMessages, PoseBeforeTheFirstFilterUpdateHasNoFilterTime) {
  PoseRecord p = sample_pose();
  p.has_filter_update = false;
  p.status = PoseStatus::kInitialising;
  const auto m = to_lcm_pose(p, Frames{"world", "imu"}, TimeBase{kUnixOffset}, 0);
  EXPECT_EQ(m.filter_time_ns, 0);
  EXPECT_EQ(m.status, ::livod::pose_t::STATUS_INITIALISING);
}

TEST(LcmMessages, StatusAndSourceCodesAreTheMessageConstants) {
  EXPECT_EQ(status_code(PoseStatus::kInitialising), 0);
  EXPECT_EQ(status_code(PoseStatus::kOk), 1);
  EXPECT_EQ(status_code(PoseStatus::kDegenerate), 2);
  EXPECT_EQ(status_code(PoseStatus::kImuOnly), 3);
  EXPECT_EQ(status_code(PoseStatus::kOk), ::livod::pose_t::STATUS_OK);
  EXPECT_EQ(status_code(PoseStatus::kImuOnly), ::livod::pose_t::STATUS_IMU_ONLY);
  EXPECT_EQ(source_code(PoseSource::kFilter), ::livod::pose_t::SOURCE_FILTER);
  EXPECT_EQ(source_code(PoseSource::kImuPropagated), ::livod::pose_t::SOURCE_IMU_PROPAGATED);
  EXPECT_NE(::livod::pose_t::SOURCE_FILTER, ::livod::pose_t::SOURCE_IMU_PROPAGATED);
  EXPECT_EQ(state_code(SensorState::kWaiting), ::livod::sensor_health_t::STATE_WAITING);
  EXPECT_EQ(state_code(SensorState::kStreaming), ::livod::sensor_health_t::STATE_STREAMING);
  EXPECT_EQ(state_code(SensorState::kStale), ::livod::sensor_health_t::STATE_STALE);
  EXPECT_EQ(clock_quality_code(ClockQuality::kCoarse), ::livod::sensor_health_t::CLOCK_COARSE);
  EXPECT_EQ(clock_quality_code(ClockQuality::kFine), ::livod::sensor_health_t::CLOCK_FINE);
  EXPECT_EQ(clock_quality_code(ClockQuality::kLost), ::livod::sensor_health_t::CLOCK_LOST);
  EXPECT_EQ(thread_state_code(ThreadState::kAlive), ::livod::thread_health_t::STATE_ALIVE);
  EXPECT_EQ(thread_state_code(ThreadState::kStuck), ::livod::thread_health_t::STATE_STUCK);
}

TEST(LcmMessages, QuaternionOfKnownRotations) {
  // 90 degrees about z: (cos 45, 0, 0, sin 45).
  const Eigen::Quaterniond qz = unit_quaternion(rot(M_PI / 2, Eigen::Vector3d::UnitZ()));
  EXPECT_NEAR(qz.w(), std::sqrt(0.5), 1e-15);
  EXPECT_NEAR(qz.x(), 0.0, 1e-15);
  EXPECT_NEAR(qz.y(), 0.0, 1e-15);
  EXPECT_NEAR(qz.z(), std::sqrt(0.5), 1e-15);
  // Identity.
  const Eigen::Quaterniond qi = unit_quaternion(Eigen::Matrix3d::Identity());
  EXPECT_EQ(qi.w(), 1.0);
  EXPECT_EQ(qi.vec(), Eigen::Vector3d::Zero());
  // 180 degrees about x, written out by hand: diag(1, -1, -1) -> (0, +-1, 0, 0).
  Eigen::Matrix3d flip = Eigen::Matrix3d::Zero();
  flip.diagonal() << 1.0, -1.0, -1.0;
  const Eigen::Quaterniond qx = unit_quaternion(flip);
  EXPECT_NEAR(qx.w(), 0.0, 1e-15);
  EXPECT_NEAR(std::abs(qx.x()), 1.0, 1e-15);
  // A rotation by 300 degrees is also one by -60: Eigen may give w < 0 for some inputs; the
  // message always has w >= 0.
  const Eigen::Quaterniond q300 = unit_quaternion(rot(5 * M_PI / 3, {0.3, 0.4, 0.5}));
  EXPECT_GE(q300.w(), 0.0);
  EXPECT_NEAR(q300.w(), std::cos(M_PI / 6), 1e-14);
}

TEST(LcmMessages, PublishedQuaternionRotatesBodyVectorsIntoTheWorld) {
  std::mt19937 rng(7);
  std::normal_distribution<double> n(0.0, 1.0);
  for (int k = 0; k < 200; ++k) {
    const Eigen::Vector3d axis(n(rng), n(rng), n(rng));
    const double angle = std::uniform_real_distribution<double>(-M_PI, M_PI)(rng);
    PoseRecord p;
    p.R_world_body = rot(angle, axis);
    const auto m = to_lcm_pose(p, Frames{}, TimeBase{}, 0);
    // Hamilton product with (w, x, y, z) as sent: q v q*.
    const Eigen::Quaterniond q(m.orientation[0], m.orientation[1], m.orientation[2],
                               m.orientation[3]);
    const Eigen::Vector3d v_body(n(rng), n(rng), n(rng));
    EXPECT_TRUE((q * v_body).isApprox(p.R_world_body * v_body, 1e-12));
    EXPECT_GE(m.orientation[0], 0.0);
    // bot_core.pose_t carries the same quaternion.
    const auto b = to_bot_core_pose(p, TimeBase{});
    for (int i = 0; i < 4; ++i) EXPECT_EQ(b.orientation[i], m.orientation[i]);
  }
}

TEST(LcmMessages, BotCorePoseUsesLibbotFrames) {
  PoseRecord p = sample_pose();
  p.R_world_body = rot(M_PI / 2, Eigen::Vector3d::UnitZ());
  p.omega_body = {1.0, 0.0, 0.0};  // about the body x axis = the world y axis
  const ::bot_core::pose_t b = to_bot_core_pose(p, TimeBase{kUnixOffset});
  EXPECT_EQ(b.utime, (kUnixOffset + p.t.ns) / 1000);
  for (int i = 0; i < 3; ++i) {
    EXPECT_EQ(b.pos[i], p.p_world_body[i]);
    EXPECT_EQ(b.vel[i], p.v_world[i]);
    EXPECT_EQ(b.accel[i], p.accel_world[i]);
  }
  EXPECT_NEAR(b.rotation_rate[0], 0.0, 1e-15);
  EXPECT_NEAR(b.rotation_rate[1], 1.0, 1e-15);
  EXPECT_NEAR(b.rotation_rate[2], 0.0, 1e-15);
  expect_round_trip(b);
}

// ---- covariance: order and frames --------------------------------------------------------------

estimator::StateMatrix random_covariance(std::mt19937& rng) {
  std::normal_distribution<double> n(0.0, 1.0);
  estimator::StateMatrix A;
  for (int r = 0; r < estimator::kStateDim; ++r) {
    for (int c = 0; c < estimator::kStateDim; ++c) A(r, c) = n(rng);
  }
  estimator::StateMatrix P = 1e-4 * A * A.transpose();
  P.diagonal().array() += 1e-6;
  return P;
}

TEST(LcmMessages, PoseCovarianceIsTheRotationThenPositionBlockOfP) {
  std::mt19937 rng(3);
  const estimator::StateMatrix P = random_covariance(rng);
  estimator::State x;
  x.R_world_imu = rot(1.0, {0.0, 1.0, 1.0});
  const PoseRecord r = pose_record_from_state(x, P, MappedTime(5), PoseSource::kFilter,
                                              PoseStatus::kOk, MappedTime(5), nullptr);
  const auto m = to_lcm_pose(r, Frames{}, TimeBase{}, 0);
  for (int i = 0; i < 3; ++i) {
    for (int j = 0; j < 3; ++j) {
      EXPECT_EQ(m.covariance[i][j], P(estimator::kRot + i, estimator::kRot + j));
      EXPECT_EQ(m.covariance[i][3 + j], P(estimator::kRot + i, estimator::kPos + j));
      EXPECT_EQ(m.covariance[3 + i][j], P(estimator::kPos + i, estimator::kRot + j));
      EXPECT_EQ(m.covariance[3 + i][3 + j], P(estimator::kPos + i, estimator::kPos + j));
    }
  }
}

// The documented meaning, checked by sampling: draw errors dx ~ N(0, P), perturb the state the way
// the filter does (State::boxplus), and measure the pose error as docs/lcm.md defines it:
// dtheta = Log(R_est^T R) (body frame, right perturbation), dp = p - p_est (world frame). Its
// sample covariance must be the published matrix; the world-frame reading Log(R R_est^T) must not.
TEST(LcmMessages, PoseCovarianceIsRightPerturbationRotationThenWorldPosition) {
  std::mt19937 rng(11);
  std::normal_distribution<double> n(0.0, 1.0);
  estimator::StateMatrix P = estimator::StateMatrix::Identity() * 1e-6;
  // Anisotropic rotation uncertainty (mostly about the body x axis), correlated with position.
  Eigen::Matrix<double, 6, 6> C = Eigen::Matrix<double, 6, 6>::Zero();
  C.diagonal() << 4e-3, 1e-5, 2e-5, 1e-2, 4e-2, 9e-3;
  C(0, 4) = C(4, 0) = 0.5 * std::sqrt(4e-3 * 4e-2);
  P.block<3, 3>(estimator::kRot, estimator::kRot) = C.block<3, 3>(0, 0);
  P.block<3, 3>(estimator::kRot, estimator::kPos) = C.block<3, 3>(0, 3);
  P.block<3, 3>(estimator::kPos, estimator::kRot) = C.block<3, 3>(3, 0);
  P.block<3, 3>(estimator::kPos, estimator::kPos) = C.block<3, 3>(3, 3);

  estimator::State x;
  x.R_world_imu = rot(M_PI / 2, Eigen::Vector3d::UnitZ());  // body x = world y
  x.p_world_imu = {10.0, -3.0, 1.0};
  const auto m = to_lcm_pose(pose_record_from_state(x, P, MappedTime(0), PoseSource::kFilter,
                                                    PoseStatus::kOk, MappedTime(0), nullptr),
                             Frames{}, TimeBase{}, 0);
  Eigen::Matrix<double, 6, 6> published;
  for (int r = 0; r < 6; ++r) {
    for (int c = 0; c < 6; ++c) published(r, c) = m.covariance[r][c];
  }

  const Eigen::LLT<estimator::StateMatrix> llt(P);
  const estimator::StateMatrix L = llt.matrixL();
  constexpr int kSamples = 40000;
  Eigen::Matrix<double, 6, 6> body = Eigen::Matrix<double, 6, 6>::Zero();
  Eigen::Matrix<double, 6, 6> world = Eigen::Matrix<double, 6, 6>::Zero();
  for (int k = 0; k < kSamples; ++k) {
    estimator::StateVector z;
    for (int i = 0; i < estimator::kStateDim; ++i) z(i) = n(rng);
    const estimator::State y = x.boxplus(L * z);
    Eigen::Matrix<double, 6, 1> e_body;
    Eigen::Matrix<double, 6, 1> e_world;
    e_body << so3::log(x.R_world_imu.transpose() * y.R_world_imu), y.p_world_imu - x.p_world_imu;
    e_world << so3::log(y.R_world_imu * x.R_world_imu.transpose()), y.p_world_imu - x.p_world_imu;
    body += e_body * e_body.transpose();
    world += e_world * e_world.transpose();
  }
  body /= kSamples;
  world /= kSamples;
  // Sampling error of a covariance entry ~ sqrt(2 / N) of its scale (0.7 %); allow 5 %.
  for (int r = 0; r < 6; ++r) {
    for (int c = 0; c < 6; ++c) {
      const double scale = std::sqrt(published(r, r) * published(c, c));
      EXPECT_NEAR(body(r, c), published(r, c), 0.05 * scale) << "entry " << r << "," << c;
    }
  }
  // The world-frame reading puts the large rotation variance on world y, not x.
  EXPECT_GT(std::abs(world(0, 0) - published(0, 0)), 0.5 * published(0, 0));
}

TEST(LcmMessages, PoseFromStateRemovesBiasesAndGravity) {
  estimator::State x;
  x.R_world_imu = rot(0.4, {1.0, 2.0, 3.0});
  x.p_world_imu = {1.0, 2.0, 3.0};
  x.v_world = {0.1, 0.2, 0.3};
  x.bias_gyro = {0.001, -0.002, 0.003};
  x.bias_accel = {0.05, -0.04, 0.03};
  x.gravity_world = {0.0, 0.0, -9.81};
  // A platform accelerating at a_world and turning at omega: what its IMU measures.
  const Eigen::Vector3d a_world(0.5, -0.25, 0.125);
  const Eigen::Vector3d omega(0.2, -0.1, 0.3);
  ImuSample imu;
  imu.gyro_rad_s = omega + x.bias_gyro;
  imu.accel_m_s2 = x.R_world_imu.transpose() * (a_world - x.gravity_world) + x.bias_accel;

  const PoseRecord r =
      pose_record_from_state(x, estimator::StateMatrix::Identity(), MappedTime(100),
                             PoseSource::kImuPropagated, PoseStatus::kOk, MappedTime(50), &imu);
  EXPECT_EQ(r.t.ns, 100);
  EXPECT_EQ(r.filter_t.ns, 50);
  EXPECT_TRUE(r.has_filter_update);
  EXPECT_EQ(r.source, PoseSource::kImuPropagated);
  EXPECT_TRUE(r.R_world_body.isApprox(x.R_world_imu));
  EXPECT_EQ(r.p_world_body, x.p_world_imu);
  EXPECT_EQ(r.v_world, x.v_world);
  EXPECT_TRUE(r.omega_body.isApprox(omega, 1e-12));
  EXPECT_TRUE(r.accel_world.isApprox(a_world, 1e-12));

  const PoseRecord none =
      pose_record_from_state(x, estimator::StateMatrix::Identity(), MappedTime(100),
                             PoseSource::kFilter, PoseStatus::kInitialising, std::nullopt, nullptr);
  EXPECT_FALSE(none.has_filter_update);
  EXPECT_EQ(none.omega_body, Eigen::Vector3d::Zero());
  EXPECT_EQ(none.accel_world, Eigen::Vector3d::Zero());
}

// ---- health -------------------------------------------------------------------------------------

HealthRecord sample_health() {
  HealthRecord h;
  h.unix_time_ns = kUnixOffset + 987'654'321;
  h.host_time = HostTime(55'000'000'123);
  h.version = "0.1.0";
  h.uptime_ns = 3'600'000'000'000;
  h.rss_bytes = 123'456'789;
  EstimatorHealthRecord& e = h.estimator;
  e.status = PoseStatus::kImuOnly;
  e.init_status = "";
  e.frame_time_p50_ms = 12.5;
  e.frame_time_p99_ms = 30.25;
  e.frame_time_max_ms = 41.0;
  e.scans_in = 1001;
  e.scans_processed = 990;
  e.scan_queue_depth = 2;
  e.imu_queue_depth = 150;
  e.scans_dropped_queue = 3;
  e.scans_out_of_order = 4;
  e.scans_before_init = 5;
  e.imu_dropped_queue = 6;
  e.imu_out_of_order = 7;
  e.frames_without_update = 8;
  e.degenerate_frames = 9;
  e.scans_not_mapped = 11;
  e.translation_ratio = 0.125;
  e.map_voxels = 1000;
  e.map_planes = 800;
  e.map_points = 50000;
  e.map_bytes = std::numeric_limits<std::uint64_t>::max();  // saturates

  SensorHealthRecord s;
  s.name = "os1";
  s.kind = "ouster";
  s.state = SensorState::kStale;
  s.last_data_age_ns = 2'500'000'000;
  s.stale_events = 1;
  s.recoveries = 2;
  s.packets_per_s = 1280.0;
  s.points_per_s = 655360.0;
  s.imu_per_s = 100.0;
  s.scans_per_s = 10.0;
  s.kernel_drops = 11;
  s.ring_overruns = 12;
  s.sequence_gaps = 13;
  s.truncated = 14;
  s.decode_errors = 15;
  s.receive_errors = 16;
  s.late_points = 17;
  s.incomplete_scans = 18;
  s.clock_mode = "free_running";
  s.clock_quality = ClockQuality::kFine;
  s.clock_offset_ns = -1'234'567;
  s.clock_skew_ppm = -48.5;
  s.clock_jitter_ns = 25'000;
  s.clock_delay_ns = 80'000;
  s.clock_resets = 19;
  s.clock_sync_losses = 20;
  s.device_state = "STREAMING";
  s.reconnects = 21;
  s.sensor_reinits = 22;
  s.last_error = "metadata fetch timed out";
  StreamHealthRecord st;
  st.name = "lidar";
  st.state = SensorState::kStreaming;
  st.last_packet_age_ns = 700'000;
  st.packets_per_s = 1280.0;
  st.megabits_per_s = 42.5;
  st.packets = 100'000;
  st.kernel_drops = 23;
  st.ring_overruns = 24;
  st.truncated = 25;
  st.receive_errors = 26;
  s.streams = {st, st};
  s.streams[1].name = "imu";
  s.streams[1].state = SensorState::kStale;
  h.sensors = {s, s};
  h.sensors[1].name = "imu0";
  h.sensors[1].streams.clear();

  h.threads = {{"scheduler", ThreadState::kAlive, 1'000'000, 5000, 2'000'000'000},
               {"publisher", ThreadState::kStuck, 3'000'000'000, 77, 2'000'000'000}};
  h.channels = {{"LIVOD_POSE", 100, 1, 40000}, {"LIVOD_HEALTH", 10, 0, 9000}};
  return h;
}

TEST(LcmMessages, HealthCarriesEveryField) {
  const HealthRecord h = sample_health();
  const ::livod::health_t m = to_lcm_health(h, 7);
  EXPECT_EQ(m.time_ns, h.unix_time_ns);
  EXPECT_EQ(m.utime, h.unix_time_ns / 1000);
  EXPECT_EQ(m.host_time_ns, 55'000'000'123);
  EXPECT_EQ(m.sequence, 7);
  EXPECT_EQ(m.version, "0.1.0");
  EXPECT_EQ(m.uptime_ns, 3'600'000'000'000);
  EXPECT_EQ(m.rss_bytes, 123'456'789);

  const auto& e = m.estimator;
  EXPECT_EQ(e.status, ::livod::pose_t::STATUS_IMU_ONLY);
  EXPECT_EQ(e.init_status, "");
  EXPECT_EQ(e.frame_time_p50_ms, 12.5);
  EXPECT_EQ(e.frame_time_p99_ms, 30.25);
  EXPECT_EQ(e.frame_time_max_ms, 41.0);
  EXPECT_EQ(e.scans_in, 1001);
  EXPECT_EQ(e.scans_processed, 990);
  EXPECT_EQ(e.scan_queue_depth, 2);
  EXPECT_EQ(e.imu_queue_depth, 150);
  EXPECT_EQ(e.scans_dropped_queue, 3);
  EXPECT_EQ(e.scans_out_of_order, 4);
  EXPECT_EQ(e.scans_before_init, 5);
  EXPECT_EQ(e.imu_dropped_queue, 6);
  EXPECT_EQ(e.imu_out_of_order, 7);
  EXPECT_EQ(e.frames_without_update, 8);
  EXPECT_EQ(e.degenerate_frames, 9);
  EXPECT_EQ(e.scans_not_mapped, 11);
  EXPECT_EQ(e.translation_ratio, 0.125);
  EXPECT_EQ(e.map_voxels, 1000);
  EXPECT_EQ(e.map_planes, 800);
  EXPECT_EQ(e.map_points, 50000);
  EXPECT_EQ(e.map_bytes, std::numeric_limits<std::int64_t>::max());

  ASSERT_EQ(m.num_sensors, 2);
  ASSERT_EQ(m.sensors.size(), 2u);
  const auto& s = m.sensors[0];
  EXPECT_EQ(s.name, "os1");
  EXPECT_EQ(s.kind, "ouster");
  EXPECT_EQ(s.state, ::livod::sensor_health_t::STATE_STALE);
  EXPECT_EQ(s.last_data_age_ns, 2'500'000'000);
  EXPECT_EQ(s.stale_events, 1);
  EXPECT_EQ(s.recoveries, 2);
  EXPECT_EQ(s.packets_per_s, 1280.0);
  EXPECT_EQ(s.points_per_s, 655360.0);
  EXPECT_EQ(s.imu_per_s, 100.0);
  EXPECT_EQ(s.scans_per_s, 10.0);
  EXPECT_EQ(s.kernel_drops, 11);
  EXPECT_EQ(s.ring_overruns, 12);
  EXPECT_EQ(s.sequence_gaps, 13);
  EXPECT_EQ(s.truncated, 14);
  EXPECT_EQ(s.decode_errors, 15);
  EXPECT_EQ(s.receive_errors, 16);
  EXPECT_EQ(s.late_points, 17);
  EXPECT_EQ(s.incomplete_scans, 18);
  EXPECT_EQ(s.clock_mode, "free_running");
  EXPECT_EQ(s.clock_quality, ::livod::sensor_health_t::CLOCK_FINE);
  EXPECT_EQ(s.clock_offset_ns, -1'234'567);
  EXPECT_EQ(s.clock_skew_ppm, -48.5);
  EXPECT_EQ(s.clock_jitter_ns, 25'000);
  EXPECT_EQ(s.clock_delay_ns, 80'000);
  EXPECT_EQ(s.clock_resets, 19);
  EXPECT_EQ(s.clock_sync_losses, 20);
  EXPECT_EQ(s.device_state, "STREAMING");
  EXPECT_EQ(s.reconnects, 21);
  EXPECT_EQ(s.sensor_reinits, 22);
  EXPECT_EQ(s.last_error, "metadata fetch timed out");
  ASSERT_EQ(s.num_streams, 2);
  const auto& st = s.streams[0];
  EXPECT_EQ(st.name, "lidar");
  EXPECT_EQ(st.state, ::livod::sensor_health_t::STATE_STREAMING);
  EXPECT_EQ(st.last_packet_age_ns, 700'000);
  EXPECT_EQ(st.packets_per_s, 1280.0);
  EXPECT_EQ(st.megabits_per_s, 42.5);
  EXPECT_EQ(st.packets, 100'000);
  EXPECT_EQ(st.kernel_drops, 23);
  EXPECT_EQ(st.ring_overruns, 24);
  EXPECT_EQ(st.truncated, 25);
  EXPECT_EQ(st.receive_errors, 26);
  EXPECT_EQ(s.streams[1].name, "imu");
  EXPECT_EQ(s.streams[1].state, ::livod::sensor_health_t::STATE_STALE);
  EXPECT_EQ(m.sensors[1].name, "imu0");
  EXPECT_EQ(m.sensors[1].num_streams, 0);

  ASSERT_EQ(m.num_threads, 2);
  EXPECT_EQ(m.threads[0].name, "scheduler");
  EXPECT_EQ(m.threads[0].state, ::livod::thread_health_t::STATE_ALIVE);
  EXPECT_EQ(m.threads[0].heartbeat_age_ns, 1'000'000);
  EXPECT_EQ(m.threads[0].heartbeats, 5000);
  EXPECT_EQ(m.threads[0].stuck_after_ns, 2'000'000'000);
  EXPECT_EQ(m.threads[1].state, ::livod::thread_health_t::STATE_STUCK);
  EXPECT_EQ(m.threads[1].heartbeat_age_ns, 3'000'000'000);

  ASSERT_EQ(m.num_channels, 2);
  EXPECT_EQ(m.channels[0].name, "LIVOD_POSE");
  EXPECT_EQ(m.channels[0].published, 100);
  EXPECT_EQ(m.channels[0].failed, 1);
  EXPECT_EQ(m.channels[0].bytes, 40000);
  EXPECT_EQ(m.channels[1].name, "LIVOD_HEALTH");
  expect_round_trip(m);
}

TEST(LcmMessages, EmptyHealthEncodes) {
  const ::livod::health_t m = to_lcm_health(HealthRecord{}, 0);
  EXPECT_EQ(m.num_sensors, 0);
  EXPECT_EQ(m.num_threads, 0);
  EXPECT_EQ(m.num_channels, 0);
  expect_round_trip(m);
}

TEST(LcmMessages, SensorHealthFromCaptureAndClock) {
  drivers::capture::SourceHealth src;
  src.name = "hdl32";
  drivers::capture::StreamHealth lidar;
  lidar.name = "lidar";
  lidar.state = drivers::capture::StreamState::kStreaming;
  lidar.packets_per_s = 1808.0;
  lidar.megabits_per_s = 18.0;
  lidar.last_packet_age = std::chrono::microseconds(400);
  lidar.stale_events = 1;
  lidar.recoveries = 1;
  lidar.capture.datagrams = 5000;
  lidar.capture.kernel_drops = 3;
  lidar.capture.ring_overruns = 4;
  lidar.capture.truncated = 5;
  lidar.capture.receive_errors = 6;
  drivers::capture::StreamHealth position = lidar;
  position.name = "position";
  position.state = drivers::capture::StreamState::kWaiting;
  position.packets_per_s = 0.0;
  position.last_packet_age.reset();
  position.capture = {};
  position.capture.kernel_drops = 10;
  src.streams = {lidar, position};
  src.decoder.sequence_gaps = 7;
  src.decoder.decode_errors = 8;
  src.decoder.late_points = 9;
  src.decoder.incomplete_scans = 2;
  src.device_state = "";
  src.reconnects = 0;
  src.sensor_reinits = 3;
  src.last_error = "x";
  ClockDomainStats clock;
  clock.mode = ClockMode::free_running;
  clock.quality = SyncQuality::fine;
  clock.offset = std::chrono::nanoseconds(-5000);
  clock.skew_ppm = 12.5;
  clock.jitter = std::chrono::nanoseconds(300);
  clock.residual_median = std::chrono::nanoseconds(900);
  clock.resets = 1;
  clock.sync_losses = 0;

  const SensorHealthRecord r = sensor_health_record(src, "velodyne", &clock, {6e5, 0.0, 10.0});
  EXPECT_EQ(r.name, "hdl32");
  EXPECT_EQ(r.kind, "velodyne");
  EXPECT_EQ(r.state, SensorState::kWaiting);  // worst of STREAMING and WAITING
  EXPECT_EQ(r.last_data_age_ns, 400'000);
  EXPECT_EQ(r.packets_per_s, 1808.0);
  EXPECT_EQ(r.points_per_s, 6e5);
  EXPECT_EQ(r.scans_per_s, 10.0);
  EXPECT_EQ(r.kernel_drops, 13u);
  EXPECT_EQ(r.ring_overruns, 4u);
  EXPECT_EQ(r.truncated, 5u);
  EXPECT_EQ(r.receive_errors, 6u);
  EXPECT_EQ(r.sequence_gaps, 7u);
  EXPECT_EQ(r.decode_errors, 8u);
  EXPECT_EQ(r.late_points, 9u);
  EXPECT_EQ(r.incomplete_scans, 2u);
  EXPECT_EQ(r.stale_events, 2u);
  EXPECT_EQ(r.clock_mode, "free_running");
  EXPECT_EQ(r.clock_quality, ClockQuality::kFine);
  EXPECT_EQ(r.clock_offset_ns, -5000);
  EXPECT_EQ(r.clock_skew_ppm, 12.5);
  EXPECT_EQ(r.clock_jitter_ns, 300);
  EXPECT_EQ(r.clock_delay_ns, 900);
  EXPECT_EQ(r.clock_resets, 1u);
  EXPECT_EQ(r.sensor_reinits, 3u);
  EXPECT_EQ(r.last_error, "x");
  ASSERT_EQ(r.streams.size(), 2u);
  EXPECT_EQ(r.streams[0].packets, 5000u);
  EXPECT_EQ(r.streams[1].last_packet_age_ns, -1);
  EXPECT_EQ(r.streams[1].state, SensorState::kWaiting);

  // A stale stream makes the sensor stale; no clock leaves the clock fields empty.
  src.streams[1].state = drivers::capture::StreamState::kStale;
  const SensorHealthRecord stale = sensor_health_record(src, "velodyne", nullptr, {});
  EXPECT_EQ(stale.state, SensorState::kStale);
  EXPECT_EQ(stale.clock_mode, "");
  EXPECT_EQ(stale.clock_offset_ns, 0);
  // All streaming -> streaming.
  src.streams[1].state = drivers::capture::StreamState::kStreaming;
  EXPECT_EQ(sensor_health_record(src, "velodyne", nullptr, {}).state, SensorState::kStreaming);
}

// ---- cloud --------------------------------------------------------------------------------------

CloudRecord cloud_of(std::size_t n) {
  CloudRecord c;
  c.t = MappedTime(2'000'000'500);
  for (std::size_t i = 0; i < n; ++i) {
    const auto f = static_cast<float>(i);
    c.points.push_back({f, -f, 0.5F * f, 1000.0F + f});
  }
  return c;
}

float float_at(const std::vector<std::uint8_t>& data, std::size_t offset) {
  std::uint32_t bits = 0;
  for (int i = 0; i < 4; ++i) bits |= std::uint32_t{data[offset + i]} << (8 * i);  // little-endian
  return std::bit_cast<float>(bits);
}

TEST(LcmMessages, CloudFieldLayout) {
  const ::livod::cloud_t m = to_lcm_cloud(cloud_of(3), "world", TimeBase{kUnixOffset}, 9, 100);
  EXPECT_EQ(m.time_ns, kUnixOffset + 2'000'000'500);
  EXPECT_EQ(m.utime, (kUnixOffset + 2'000'000'500) / 1000);
  EXPECT_EQ(m.mapped_time_ns, 2'000'000'500);
  EXPECT_EQ(m.sequence, 9);
  EXPECT_EQ(m.frame, "world");
  ASSERT_EQ(m.num_fields, 4);
  const char* names[] = {"x", "y", "z", "intensity"};
  for (int i = 0; i < 4; ++i) {
    EXPECT_EQ(m.fields[i].name, names[i]);
    EXPECT_EQ(m.fields[i].offset, 4 * i);
    EXPECT_EQ(m.fields[i].datatype, ::livod::point_field_t::FLOAT32);
    EXPECT_EQ(m.fields[i].count, 1);
  }
  EXPECT_EQ(::livod::point_field_t::FLOAT32, 7);  // sensor_msgs/PointField's code
  EXPECT_EQ(m.point_step, 16);
  EXPECT_FALSE(m.is_bigendian);
  EXPECT_EQ(m.num_points, 3);
  EXPECT_EQ(m.source_points, 3);
  ASSERT_EQ(m.data_size, 48);
  ASSERT_EQ(m.data.size(), 48u);
  EXPECT_EQ(float_at(m.data, 16 + 0), 1.0F);
  EXPECT_EQ(float_at(m.data, 16 + 4), -1.0F);
  EXPECT_EQ(float_at(m.data, 16 + 8), 0.5F);
  EXPECT_EQ(float_at(m.data, 16 + 12), 1001.0F);
  expect_round_trip(m);
}

TEST(LcmMessages, CloudDecimationBoundAndSpread) {
  for (const std::size_t n : {0UL, 1UL, 99UL, 100UL, 101UL, 1000UL, 12345UL}) {
    const CloudRecord c = cloud_of(n);
    const ::livod::cloud_t m = to_lcm_cloud(c, "world", TimeBase{}, 0, 100);
    const std::size_t kept = std::min<std::size_t>(n, 100);
    ASSERT_EQ(m.num_points, static_cast<std::int32_t>(kept)) << n;
    EXPECT_EQ(m.source_points, static_cast<std::int32_t>(n));
    ASSERT_EQ(m.data.size(), kept * 16);
    std::set<float> xs;
    float previous = -1.0F;
    for (std::size_t i = 0; i < kept; ++i) {
      const float x = float_at(m.data, i * 16);
      // Every kept point is an input point, in input order, none twice.
      const auto index = static_cast<std::size_t>(x);
      ASSERT_LT(index, n);
      EXPECT_EQ(float_at(m.data, i * 16 + 12), 1000.0F + x);
      EXPECT_GT(x, previous);
      previous = x;
      xs.insert(x);
      EXPECT_EQ(index, decimated_index(i, n, kept));
    }
    EXPECT_EQ(xs.size(), kept);
    if (kept > 0) {
      // Evenly spread: starts at the first point, the last kept point is within one stride of
      // the end.
      EXPECT_EQ(float_at(m.data, 0), 0.0F);
      EXPECT_GE(previous + static_cast<float>(n / kept) + 1.0F, static_cast<float>(n - 1));
    }
  }
  EXPECT_THROW((void)to_lcm_cloud(cloud_of(5), "world", TimeBase{}, 0, 0), std::invalid_argument);
}

}  // namespace
}  // namespace livod::daemon::publish
