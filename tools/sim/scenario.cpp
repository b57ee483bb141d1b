#include "tools/sim/scenario.hpp"

#include "core/units.hpp"

#include <array>
#include <cmath>

#include "core/error.hpp"
#include "tools/sim/plain_scenario.hpp"

namespace livod::sim {
namespace {

Eigen::Isometry3d make_pose(const Eigen::Vector3d& t, const Eigen::Matrix3d& R) {
  Eigen::Isometry3d T = Eigen::Isometry3d::Identity();
  T.linear() = R;
  T.translation() = t;
  return T;
}

Eigen::Matrix3d rpy(double roll, double pitch, double yaw) {
  return (Eigen::AngleAxisd(yaw, Eigen::Vector3d::UnitZ()) *
          Eigen::AngleAxisd(pitch, Eigen::Vector3d::UnitY()) *
          Eigen::AngleAxisd(roll, Eigen::Vector3d::UnitX()))
      .toRotationMatrix();
}

// A forward-looking camera: camera z = body x, camera x = -body y, camera y = -body z.
Eigen::Matrix3d R_body_forward_cam() {
  Eigen::Matrix3d R;
  R << 0, 0, 1, -1, 0, 0, 0, -1, 0;
  return R;
}

// FAST-LIVO2's Avia rig camera (MV-CA013, 1280x1024) at its scale 0.5: 640x512.
CameraMount rig_camera() {
  CameraMount cam;
  auto& k = cam.params.intrinsics;
  k.model = CameraIntrinsics::Model::kPinholeRadtan;
  k.width = 1280;
  k.height = 1024;
  k.fx = 1293.57;
  k.fy = 1293.32;
  k.cx = 626.91;
  k.cy = 522.80;
  k.distortion = {-0.07616, 0.123001, -0.00113, 0.000251};
  k = k.scaled(0.5);
  // Wider than the real lens so that a room is seen with enough structure: 640 px / 500 px focal.
  k.fx = 500.0;
  k.fy = 500.0;
  cam.params.rate_hz = 10.0;
  cam.T_body_cam = make_pose({0.06, 0.0, 0.04}, R_body_forward_cam());
  return cam;
}

// Handheld walk around the free centre of the room: 0.6 m/s on an ellipse, steps at 1.8 Hz.
TrajectorySpec handheld_room() {
  TrajectorySpec s;
  s.x = {0.0, 0.0, {{2.0, 0.32, 0.0}}};
  s.y = {-1.4, 0.0, {{1.4, 0.32, M_PI / 2}}};
  s.z = {1.35, 0.0, {{0.035, 11.3, 0.0}, {0.06, 0.7, 1.0}}};
  s.roll = {0.0, 0.0, {{0.05, 5.65, 0.3}, {0.04, 0.9, 0.0}}};
  s.pitch = {0.05, 0.0, {{0.06, 11.3, 0.8}, {0.08, 0.5, 0.0}}};
  s.yaw = {0.0, 0.0, {{0.35, 0.8, 0.0}, {0.03, 5.65, 0.0}}};
  s.yaw_follows_heading = true;
  s.static_duration = 2.0;
  s.ramp_duration = 2.0;
  return s;
}

// Aggressive handheld: yaw swings of +-0.85 rad at 5.8 rad/s (peak ~280 deg/s) with roll and
// pitch shakes, combined peak body rate close to 300 deg/s.
TrajectorySpec aggressive_room() {
  TrajectorySpec s;
  s.x = {0.0, 0.0, {{1.6, 0.45, 0.0}, {0.08, 9.0, 0.2}}};
  s.y = {0.0, 0.0, {{1.2, 0.6, 0.5}, {0.06, 7.5, 0.0}}};
  s.z = {1.4, 0.0, {{0.15, 1.3, 0.0}, {0.04, 11.0, 0.4}}};
  s.roll = {0.0, 0.0, {{0.30, 4.5, 0.0}}};
  s.pitch = {0.0, 0.0, {{0.25, 3.7, 0.6}}};
  s.yaw = {0.0, 0.0, {{0.85, 5.8, 0.0}, {1.5, 0.25, 0.0}}};
  s.static_duration = 2.0;
  s.ramp_duration = 2.5;
  return s;
}

// A car on the street: 10 m/s, weaving gently within the lane, heading along the velocity.
TrajectorySpec vehicle_street() {
  TrajectorySpec s;
  s.x = {0.0, 10.0, {}};
  s.y = {0.0, 0.0, {{1.2, 0.12, 0.0}, {0.3, 0.41, 0.5}}};
  s.z = {1.9, 0.0, {{0.02, 2.1, 0.0}}};
  s.roll = {0.0, 0.0, {{0.01, 1.3, 0.0}}};
  s.pitch = {0.0, 0.0, {{0.012, 1.7, 0.3}}};
  s.yaw = {0.0, 0.0, {}};
  s.yaw_follows_heading = true;
  s.static_duration = 2.0;
  s.ramp_duration = 3.0;
  return s;
}

TrajectorySpec drone_street() {
  TrajectorySpec s;
  s.x = {0.0, 5.0, {}};
  s.y = {0.0, 0.0, {{3.0, 0.2, 0.0}}};
  // 5 - 4 cos(0.15 tau): starts 1 m above the street, climbs to 9 m and comes back down.
  s.z = {5.0, 0.0, {{4.0, 0.15, -M_PI / 2}}};
  s.roll = {0.0, 0.0, {{0.08, 0.9, 0.0}}};
  s.pitch = {0.0, 0.0, {{0.1, 0.7, 0.3}}};
  s.yaw = {0.0, 0.0, {{0.6, 0.3, 0.0}}};
  s.static_duration = 2.0;
  s.ramp_duration = 3.0;
  return s;
}

TrajectorySpec corridor_walk() {
  TrajectorySpec s;
  s.x = {0.0, 1.0, {}};
  s.y = {0.0, 0.0, {{0.25, 0.4, 0.0}}};
  s.z = {1.35, 0.0, {{0.035, 11.3, 0.0}}};
  s.roll = {0.0, 0.0, {{0.04, 5.65, 0.0}}};
  s.pitch = {0.0, 0.0, {{0.05, 11.3, 0.5}}};
  s.yaw = {0.0, 0.0, {{0.2, 0.5, 0.0}}};
  s.static_duration = 2.0;
  s.ramp_duration = 2.0;
  return s;
}

constexpr double kDeg = M_PI / 180.0;

}  // namespace

// Datasheet figures (1 sigma unless stated). Where a sheet is silent the value is marked assumed.
RangeModel datasheet_range_model(const std::string& model) {
  RangeModel r;
  r.detection_limited = true;
  r.dropout_probability = 0.002;
  if (model == "OS1-64" || model == "OS1-128") {
    // Ouster OS1 datasheet (rev 6): 0.8-120 m for an 80 % target (40 m at 10 %, both in 100 klx
    // sunlight); range repeatability 1.5 cm at SNR > 250, 3 cm at SNR 100, 10 cm at SNR 12; "zero
    // bias for Lambertian targets"; beam divergence 0.13 deg FWHM (64 channels), 0.18 deg (128).
    r.sigma_m = 0.015;
    r.sigma_at_limit_m = 0.10;
    r.min_range_m = 0.8;
    r.max_range_m = 120.0;
    r.intensity_bias_m = 0.0;
    const double fwhm = (model == "OS1-128" ? 0.18 : 0.13) * kDeg;
    r.divergence_h_rad = fwhm;
    r.divergence_v_rad = fwhm;
  } else if (model == "VLP-16" || model == "HDL-32E") {
    // Velodyne VLP-16 datasheet: 100 m, accuracy +-3 cm typical; HDL-32E: 80-100 m, < 2 cm.
    // Divergence 3.0 mrad across the scan x 1.5 mrad along the column: the Velodyne manuals'
    // figure (VLS-128 manual table F-1; the VLP-16 and HDL-32E sheets give none, assumed the
    // same). Range walk: half the +-3 cm accuracy budget (assumed; intensity-dependent range
    // errors of a few cm are the known residual of Velodyne calibrations). Noise at the detection
    // limit: the Ouster curve (assumed).
    const bool vlp = model == "VLP-16";
    r.sigma_m = vlp ? 0.015 : 0.01;
    r.sigma_at_limit_m = 0.10;
    r.min_range_m = vlp ? 0.5 : 1.0;
    r.max_range_m = 100.0;
    r.intensity_bias_m = vlp ? 0.015 : 0.01;
    r.divergence_h_rad = 3.0e-3;
    r.divergence_v_rad = 1.5e-3;
  } else if (model == "PANDARXT32") {
    // Hesai PandarXT-32 datasheet (drivers/hesai/hesai_family.cpp): 0.05-120 m, range accuracy
    // +-1 cm (taken as 1 cm, 1 sigma, the Velodyne sheets' convention halved would be kinder).
    // Divergence, range walk and the noise at the limit are not in livod's sources: the
    // Velodyne figures above (assumed).
    r.sigma_m = 0.01;
    r.sigma_at_limit_m = 0.10;
    r.min_range_m = 0.05;
    r.max_range_m = 120.0;
    r.intensity_bias_m = 0.01;
    r.divergence_h_rad = 3.0e-3;
    r.divergence_v_rad = 1.5e-3;
  } else if (model == "AVIA") {
    // Livox Avia user manual: 450 m at 80 % (190 m at 10 %, 100 klx), range random error < 2 cm
    // (at 20 m), beam divergence 0.03 deg (horizontal) x 0.28 deg (vertical); distance system
    // error < +-3 cm (HAP sheet, same optics): range walk 1 cm (assumed).
    r.sigma_m = 0.02;
    r.sigma_at_limit_m = 0.08;
    r.min_range_m = 0.2;
    r.max_range_m = 450.0;
    r.intensity_bias_m = 0.01;
    r.divergence_h_rad = 0.03 * kDeg;
    r.divergence_v_rad = 0.28 * kDeg;
  } else if (model == "MID-360") {
    // Livox Mid-360 user manual: 70 m at 80 % (40 m at 10 %), range precision <= 2 cm at 10 m
    // (<= 3 cm at 0.2 m), blind zone 0.1 m. Divergence is not in its table: 0.2 deg x 0.2 deg
    // (assumed, between the Avia's axes); range walk 1 cm (assumed, as the Avia).
    r.sigma_m = 0.02;
    r.sigma_at_limit_m = 0.08;
    r.min_range_m = 0.1;
    r.max_range_m = 70.0;
    r.intensity_bias_m = 0.01;
    r.divergence_h_rad = 0.2 * kDeg;
    r.divergence_v_rad = 0.2 * kDeg;
  } else {
    r = RangeModel{};
  }
  return r;
}

RangeModel plain_range_model(const RangeModel& range) {
  RangeModel r;
  r.sigma_m = range.sigma_m;
  r.dropout_probability = range.dropout_probability;
  r.min_range_m = range.min_range_m;
  r.max_range_m = range.max_range_m;
  r.reflectivity_gain = range.reflectivity_gain;
  return r;
}

void make_plain(Scenario& scenario) {
  for (auto& lidar : scenario.lidars) lidar.range = plain_range_model(lidar.range);
  scenario.scene = SceneContent{};
}

namespace {

LidarMount ouster(const std::string& model, const std::string& name) {
  LidarMount m;
  m.model = model;
  m.name = name;
  // Body = the Ouster's internal IMU. OS1 metadata: imu_to_sensor translation
  // (6.253, -11.775, 7.645) mm, no rotation, so the sensor frame sits at minus that in the IMU.
  m.T_body_sensor = make_pose({-0.006253, 0.011775, -0.007645}, Eigen::Matrix3d::Identity());
  m.clock = ClockFaults{.offset_s = 1234.5, .skew_ppm = 30.0, .jitter_s = 0.0, .reset_at_s = -1};
  m.range = datasheet_range_model(model);
  m.imu_noise.rate_hz = 100.0;
  m.imu_noise.gyro_bias0 = Eigen::Vector3d(0.002, -0.003, 0.001);
  m.imu_noise.accel_bias0 = Eigen::Vector3d(0.02, -0.03, 0.05);
  return m;
}

LidarMount livox(const std::string& model, const std::string& name, const Eigen::Vector3d& t) {
  LidarMount m;
  m.model = model;
  m.name = name;
  m.T_body_sensor = make_pose(t, Eigen::Matrix3d::Identity());
  m.clock = ClockFaults{.offset_s = 52.25, .skew_ppm = -20.0, .jitter_s = 0.0, .reset_at_s = -1};
  m.range = datasheet_range_model(model);
  m.imu_noise.rate_hz = 200.0;
  m.imu_noise.gyro_bias0 = Eigen::Vector3d(-0.002, 0.001, 0.0025);
  m.imu_noise.accel_bias0 = Eigen::Vector3d(-0.03, 0.02, 0.04);
  return m;
}

// The HDL-32E's internal IMU is the body: the decoder reports it in the LiDAR frame (at the LiDAR
// origin), so the LiDAR -> IMU extrinsic is the identity. Noise of its motion sensors (Analog
// Devices parts, going by the scale factors: 0.09766 deg/s and 0.1453 C per LSB are the
// ADIS16080 gyro's, 1.221 mg the ADIS16003-class 12-bit accelerometer's): gyro 0.05 deg/s/sqrt(Hz)
// (ADIS16080 datasheet), accelerometer 200 ug/sqrt(Hz). Initial gyro biases are the means of the
// real monterey capture at rest (-0.092, 0.064, 0.512 rad/s: sensor 3 reads about -29 deg/s);
// its accelerometer means mix tilt and bias, so moderate accelerometer biases are used.
LidarMount hdl32e(const std::string& name) {
  LidarMount m;
  m.model = "HDL-32E";
  m.name = name;
  m.T_body_sensor = Eigen::Isometry3d::Identity();
  m.clock = ClockFaults{.offset_s = 2345.5, .skew_ppm = -25.0, .jitter_s = 0.0, .reset_at_s = -1};
  m.range = datasheet_range_model("HDL-32E");
  m.imu_noise.rate_hz = 1.0 / 4.988e-3;  // one sample per position packet (velodyne_sim.hpp)
  m.imu_noise.gyro_noise_density = 0.05 * M_PI / 180.0;
  m.imu_noise.accel_noise_density = 200e-6 * kStandardGravity;
  m.imu_noise.gyro_bias0 = Eigen::Vector3d(-0.092, 0.064, 0.512);
  m.imu_noise.accel_bias0 = Eigen::Vector3d(0.04, -0.03, 0.06);
  return m;
}

Scenario base(const std::string& name, const std::string& description, WorldKind world,
              TrajectorySpec trajectory, double duration) {
  Scenario s;
  s.name = name;
  s.description = description;
  s.world = world;
  s.trajectory = std::move(trajectory);
  s.duration_s = duration;
  // What moves and scatters (docs/simulator.md, "Realism"): a city street with some traffic and
  // people on the pavements and leafy trees and hedges; two people walking in the room.
  if (world == WorldKind::kStreet) s.scene = SceneContent{3.0, 1.5, true};
  if (world == WorldKind::kRoom) s.scene = SceneContent{2.0, 0.0, true};
  return s;
}

// The built-in scenarios, in the order they are listed.
constexpr std::array<const char*, 14> kScenarioNames{"room_handheld_os1_64",
                                                     "room_handheld_avia",
                                                     "room_handheld_mid360",
                                                     "room_aggressive_os1_64",
                                                     "street_vehicle_vlp16",
                                                     "street_vehicle_hdl32e",
                                                     "street_vehicle_os1_128",
                                                     "street_drone_os1_64",
                                                     "corridor_handheld_os1_64",
                                                     "corridor_handheld_os1_64_camera",
                                                     "room_handheld_os1_64_camera_faults",
                                                     "room_dual_mid360",
                                                     "street_vehicle_vlp16_avia",
                                                     "corridor_side_rooms_dual_avia"};

}  // namespace

std::vector<std::pair<std::string, std::string>> list_scenarios() {
  std::vector<std::pair<std::string, std::string>> out;
  for (const char* name : kScenarioNames) out.emplace_back(name, make_scenario(name).description);
  return out;
}

Scenario make_scenario(const std::string& name) {
  if (name == "room_handheld_os1_64") {
    Scenario s =
        base(name, "indoor room, handheld walk, Ouster OS1-64 + internal IMU, 640x512 camera",
             WorldKind::kRoom, handheld_room(), 30.0);
    s.lidars.push_back(ouster("OS1-64", "os1"));
    s.cameras.push_back(rig_camera());
    s.body_imu = "os1";
    return s;
  }
  if (name == "room_handheld_avia") {
    Scenario s = base(name, "indoor room, handheld walk, Livox Avia + internal IMU, 640x512 camera",
                      WorldKind::kRoom, handheld_room(), 30.0);
    s.lidars.push_back(livox("AVIA", "avia", {0.04165, 0.02326, -0.0284}));
    s.cameras.push_back(rig_camera());
    s.body_imu = "avia";
    return s;
  }
  if (name == "room_handheld_mid360") {
    Scenario s = base(name, "indoor room, handheld walk, Livox Mid-360 + internal IMU",
                      WorldKind::kRoom, handheld_room(), 30.0);
    s.lidars.push_back(livox("MID-360", "mid360", {-0.011, -0.02329, 0.04412}));
    s.body_imu = "mid360";
    return s;
  }
  if (name == "room_aggressive_os1_64") {
    Scenario s = base(name, "indoor room, aggressive handheld (up to ~300 deg/s), Ouster OS1-64",
                      WorldKind::kRoom, aggressive_room(), 30.0);
    s.lidars.push_back(ouster("OS1-64", "os1"));
    s.body_imu = "os1";
    return s;
  }
  if (name == "street_vehicle_vlp16") {
    Scenario s =
        base(name, "street, ground vehicle at 10 m/s (>= 300 m), Velodyne VLP-16 + CAN IMU",
             WorldKind::kStreet, vehicle_street(), 36.0);
    LidarMount vlp;
    vlp.model = "VLP-16";
    vlp.name = "vlp16";
    vlp.T_body_sensor = make_pose({0.1, 0.0, 0.35}, rpy(0.0, 0.02, 0.0));
    vlp.clock =
        ClockFaults{.offset_s = 1500.0, .skew_ppm = 15.0, .jitter_s = 0.0, .reset_at_s = -1};
    vlp.range = datasheet_range_model("VLP-16");
    vlp.imu = false;
    s.lidars.push_back(vlp);
    CanImuMount imu;
    imu.noise.rate_hz = 200.0;
    imu.noise.gyro_bias0 = Eigen::Vector3d(0.001, -0.002, 0.0015);
    imu.noise.accel_bias0 = Eigen::Vector3d(0.03, 0.02, -0.04);
    imu.clock = ClockFaults{.offset_s = 12.0, .skew_ppm = 40.0, .jitter_s = 0.0, .reset_at_s = -1};
    s.can_imu = imu;
    s.body_imu = imu.name;
    return s;
  }
  if (name == "street_vehicle_hdl32e") {
    Scenario s = base(name,
                      "street, ground vehicle at 10 m/s (>= 300 m), Velodyne HDL-32E + its "
                      "internal IMU",
                      WorldKind::kStreet, vehicle_street(), 36.0);
    s.lidars.push_back(hdl32e("hdl32e"));
    s.body_imu = "hdl32e";
    return s;
  }
  if (name == "street_vehicle_os1_128") {
    Scenario s = base(name, "street, ground vehicle at 10 m/s (>= 300 m), Ouster OS1-128",
                      WorldKind::kStreet, vehicle_street(), 36.0);
    s.lidars.push_back(ouster("OS1-128", "os1"));
    s.body_imu = "os1";
    return s;
  }
  if (name == "street_drone_os1_64") {
    Scenario s = base(name, "street, drone flight 1-9 m high at 5 m/s, Ouster OS1-64 + camera",
                      WorldKind::kStreet, drone_street(), 40.0);
    s.lidars.push_back(ouster("OS1-64", "os1"));
    s.cameras.push_back(rig_camera());
    s.body_imu = "os1";
    return s;
  }
  if (name == "corridor_handheld_os1_64") {
    Scenario s = base(name, "long featureless corridor (LiDAR-degenerate along x), Ouster OS1-64",
                      WorldKind::kCorridor, corridor_walk(), 30.0);
    s.lidars.push_back(ouster("OS1-64", "os1"));
    s.body_imu = "os1";
    return s;
  }
  if (name == "corridor_handheld_os1_64_camera") {
    // The corridor's walls, floor and ceiling are textured: the camera sees the motion along the
    // axis that the LiDAR cannot.
    Scenario s = base(name,
                      "long featureless corridor (LiDAR-degenerate along x) with textured walls, "
                      "Ouster OS1-64 + 640x512 camera",
                      WorldKind::kCorridor, corridor_walk(), 30.0);
    s.lidars.push_back(ouster("OS1-64", "os1"));
    s.cameras.push_back(rig_camera());
    s.body_imu = "os1";
    return s;
  }
  if (name == "room_handheld_os1_64_camera_faults") {
    // Auto-exposure-like steps (x2 at 6 s, x0.5 at 10 s) and a camera that stops for 5 s
    // (13-18 s). A fixed base exposure, low enough that the doubled one does not saturate.
    Scenario s = base(name,
                      "indoor room, handheld walk, Ouster OS1-64 + camera whose exposure steps x2 "
                      "and x0.5 and whose images stop for 5 s",
                      WorldKind::kRoom, handheld_room(), 22.0);
    s.lidars.push_back(ouster("OS1-64", "os1"));
    CameraMount cam = rig_camera();
    cam.params.exposure_s = 0.002;
    cam.params.exposure_variation = 0.0;
    cam.params.exposure_steps = {{6.0, 2.0}, {10.0, 0.5}};
    cam.params.outages = {{13.0, 18.0}};
    s.cameras.push_back(cam);
    s.body_imu = "os1";
    return s;
  }
  if (name == "room_dual_mid360") {
    // Two Mid-360s back to back, as docs/examples/dual-mid360.yaml mounts them (closer, for a
    // handheld rig): the front one's IMU is the body, the rear one is turned around and tilted
    // down, its IMU off. Their clocks differ by 1.03 s, so their 10 Hz scans are cut 30 ms apart.
    Scenario s = base(name,
                      "indoor room, handheld walk, two Livox Mid-360 facing opposite ways "
                      "(unsynchronised scans), the front one's IMU",
                      WorldKind::kRoom, handheld_room(), 30.0);
    s.lidars.push_back(livox("MID-360", "front", {-0.011, -0.02329, 0.04412}));
    LidarMount rear = livox("MID-360", "rear", {-0.35, 0.0, 0.02});
    rear.T_body_sensor.linear() = rpy(0.0, 0.3, M_PI);
    rear.clock.offset_s += 1.03;
    rear.imu = false;
    s.lidars.push_back(rear);
    s.body_imu = "front";
    return s;
  }
  if (name == "street_vehicle_vlp16_avia") {
    // The VLP-16 of street_vehicle_vlp16 on the roof plus a forward-looking Avia on the front
    // bumper, each on its own clock (scans cut 40 ms apart), the CAN IMU as the body.
    Scenario s = make_scenario("street_vehicle_vlp16");
    s.name = name;
    s.description =
        "street, ground vehicle at 10 m/s (>= 300 m), Velodyne VLP-16 (roof) + Livox Avia "
        "(bumper, forward) + CAN IMU";
    LidarMount avia = livox("AVIA", "avia", {1.8, 0.0, -0.9});
    avia.T_body_sensor.linear() = rpy(0.0, 0.05, 0.0);
    avia.clock.offset_s = 2000.04;
    avia.imu = false;
    s.lidars.push_back(avia);
    return s;
  }
  if (name == "corridor_side_rooms_dual_avia") {
    // A forward-looking Avia sees the corridor's walls, floor and ceiling and the doorways at
    // grazing angles only: nearly degenerate along x. A second Avia looking left sees into the
    // side rooms as it passes their doorways.
    Scenario s = base(name,
                      "corridor with side rooms behind doorways in its left wall, Livox Avia "
                      "looking forward (+ IMU) and Livox Avia looking left",
                      WorldKind::kCorridorSideRooms, corridor_walk(), 30.0);
    s.lidars.push_back(livox("AVIA", "forward", {0.04165, 0.02326, -0.0284}));
    LidarMount side = livox("AVIA", "side", {0.0, 0.12, 0.05});
    side.T_body_sensor.linear() = rpy(0.0, 0.0, M_PI / 2);
    side.clock.offset_s += 0.55;
    side.imu = false;
    s.lidars.push_back(side);
    s.body_imu = "forward";
    return s;
  }
  std::string known;
  for (const char* n : kScenarioNames) known += std::string(known.empty() ? "" : ", ") + n;
  throw Error("unknown scenario '" + name + "'; known scenarios: " + known);
}

}  // namespace livod::sim
