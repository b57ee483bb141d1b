#pragma once
// The whole daemon configuration as plain structs with defaults. load_config() (load_config.hpp)
// fills them from one YAML file and validates them; docs/configuration.md documents every key.
// Units are SI unless the member name says otherwise (_deg, _ppm, _bytes, _px).

#include <Eigen/Geometry>
#include <array>
#include <cstdint>
#include <filesystem>
#include <optional>
#include <set>
#include <span>
#include <string>
#include <string_view>
#include <variant>
#include <vector>

#include "drivers/lidar_family.hpp"
#include "estimator/params.hpp"

namespace livod::daemon {

// How the bytes of a sensor become measurements. dataset_* read already-decoded messages from
// recordings (ROS1 bags, EuRoC/ASL folders) and exist for public datasets; they are replay-only.
enum class Driver {
  ouster,
  velodyne,
  livox_sdk1,
  livox_sdk2,
  hesai,
  v4l2,
  aravis,
  can_imu,
  serial_imu,
  dataset_lidar,
  dataset_imu,
  dataset_camera,
};

enum class SensorKind { lidar, camera, imu };

SensorKind sensor_kind(Driver driver);
// LiDARs decoded from their UDP packets (as opposed to decoded point clouds from a recording).
bool is_packet_lidar(Driver driver);

// Which local UDP ports a sensor's streams arrive on; 0 = the driver has no such stream (the
// LiDAR families' tables give the defaults: drivers/lidar_family.hpp).
using UdpPorts = drivers::UdpPorts;

struct UdpSourceConfig {
  std::string bind_address = "0.0.0.0";
  std::string sensor_address;   // IPv4 or host name; empty = accept any sender
  UdpPorts ports;               // defaults depend on driver and model
  std::string multicast_group;  // empty = unicast/broadcast
  int socket_buffer_bytes = 8 * 1024 * 1024;
};

enum class ReplayFormat { pcap, candump, rosbag1, euroc, serial };

struct ReplaySourceConfig {
  std::filesystem::path file;  // absolute (resolved against the config file's folder)
  ReplayFormat format = ReplayFormat::pcap;
  std::string topic;  // rosbag1 only
};

// A local device: V4L2 node or serial port (path), GigE/USB3 Vision camera (camera_id, empty =
// the first camera found) or CAN interface (interface).
struct DeviceSourceConfig {
  std::string path;
  std::string camera_id;
  std::string interface;
};

using SourceConfig = std::variant<UdpSourceConfig, ReplaySourceConfig, DeviceSourceConfig>;

enum class FrameCutMode { azimuth, time, frame_id };

// Where one LiDAR scan ends and the next begins.
struct FrameCutConfig {
  FrameCutMode mode = FrameCutMode::time;  // default depends on the driver
  double azimuth_deg = 0.0;                // mode azimuth: cut where the azimuth crosses this
  double period_s = 0.1;                   // mode time: scan duration
};

// The extrinsic as written in the file. relative_to names the reference frame (empty = body);
// T_reference_sensor is already inverted when the file gave T_sensor_reference (inverse: true).
struct ExtrinsicConfig {
  std::string relative_to;
  bool inverse = false;
  Eigen::Isometry3d T_reference_sensor = Eigen::Isometry3d::Identity();
};

enum class ClockMode { automatic, direct, free_running, receive_time };

struct ClockConfig {
  ClockMode mode = ClockMode::automatic;
  double latency_s = 0.0;       // receive_time mode: subtracted from the receive time
  double window_s = 60.0;       // free_running mode: convex-hull window
  double max_skew_ppm = 200.0;  // free_running mode: |rate - 1| bound
};

// The IMU built into a LiDAR (Ouster, Livox). Its name in body_frame is "<sensor>.imu".
struct InternalImuConfig {
  bool enabled = false;  // default: true when the model has one
};

enum class CameraModel { pinhole, equidistant };
enum class CameraPixelFormat { mono8, mono16, bgr8 };
enum class CameraTimestamp { automatic, start_of_exposure, end_of_frame };
enum class CameraTrigger { free_run, software, hardware };

struct CameraConfig {
  CameraModel model = CameraModel::pinhole;
  int width = 0;                       // px, full resolution
  int height = 0;                      // px
  std::array<double, 4> intrinsics{};  // fx, fy, cx, cy at full resolution (px)
  // pinhole: radial-tangential k1 k2 p1 p2 [k3] or empty; equidistant: k1 k2 k3 k4.
  std::vector<double> distortion;
  double scale = 1.0;                   // images (and intrinsics) are resized by this
  std::optional<double> exposure_s;     // fixed exposure; unset = leave the camera's setting
  std::optional<double> frame_rate_hz;  // unset = leave the camera's setting
  int decimation = 1;                   // keep every n-th frame

  // Live capture (v4l2, aravis; docs/drivers/camera.md).
  CameraPixelFormat pixel_format = CameraPixelFormat::mono8;
  std::optional<double> gain;  // camera units (GenICam: usually dB; V4L2: driver units)
  int buffers = 0;             // driver buffers; 0 = the driver's default (V4L2 4, Aravis 8)
  CameraTimestamp timestamp = CameraTimestamp::automatic;  // which instant the stamps mark
  double readout_s = 0.0;  // end-of-frame stamps: end of exposure -> stamp (readout + transfer)
  std::vector<std::string> v4l2_formats;  // v4l2: wire formats (fourcc) to ask for, best first
  CameraTrigger trigger = CameraTrigger::free_run;  // aravis
  std::string trigger_line = "Line1";               // aravis, hardware trigger input
  int packet_size = 0;                              // aravis GigE: 0 = negotiate
  bool packet_resend = true;                        // aravis GigE
  bool ptp = false;                                 // aravis: enable IEEE 1588 in the camera
  bool chunk_exposure = true;                       // aravis: per-frame exposure from chunks
};

enum class CanDecoder { bosch_mm7, sbg, custom };
enum class CanQuantity { accel_x, accel_y, accel_z, gyro_x, gyro_y, gyro_z };
enum class CanUnit { m_s2, g, rad_s, deg_s };

// One signal of a custom CAN IMU (DBC-style: raw * factor + offset, in `unit`).
struct CanSignal {
  CanQuantity quantity = CanQuantity::accel_x;
  std::uint32_t id = 0;  // 11-bit when <= 0x7FF, else 29-bit extended
  int start_bit = 0;
  int length = 16;
  bool is_signed = false;
  bool big_endian = false;
  double factor = 1.0;
  double offset = 0.0;
  CanUnit unit = CanUnit::m_s2;
};

struct SbgCanIds {
  std::uint32_t info = 0x120;
  std::uint32_t accel = 0x121;
  std::uint32_t gyro = 0x122;
};

struct CanConfig {
  CanDecoder decoder = CanDecoder::bosch_mm7;
  SbgCanIds sbg_ids;
  std::vector<CanSignal> signals;  // custom: exactly one per quantity
  std::uint32_t sample_id = 0;     // custom: the frame whose arrival completes a sample
  bool fd_frames = false;          // live: also receive CAN FD frames
};

enum class SerialProtocol { xsens_mtdata2, vectornav_binary };

struct SerialConfig {
  SerialProtocol protocol = SerialProtocol::xsens_mtdata2;
  int baud_rate = 115200;
};

enum class TimeUnit { ns, us, ms, s };
enum class TimeReference { relative, absolute };
enum class ScanStamp { start, end };

// How decoded messages from a recording are to be read (dataset_* drivers).
struct DatasetConfig {
  std::string time_field = "t";  // dataset_lidar: per-point time field of PointCloud2
  TimeUnit time_unit = TimeUnit::ns;
  TimeReference time_reference = TimeReference::relative;  // relative to the header stamp
  ScanStamp stamp = ScanStamp::start;  // what the header stamp marks (NTU-VIRAL: end)
  CanUnit accel_unit = CanUnit::m_s2;  // dataset_imu (Livox bags record g)
  CanUnit gyro_unit = CanUnit::rad_s;
};

struct SensorConfig {
  std::string name;
  Driver driver = Driver::ouster;
  std::string model;  // canonical spelling for LiDARs (e.g. "OS1-64", "VLP-16", "PANDARXT32")
  bool enabled = true;
  SourceConfig source;
  std::filesystem::path metadata;         // ouster: metadata JSON (empty = fetch over HTTP)
  std::filesystem::path calibration;      // velodyne: XML/YAML (empty = built-in); hesai: angle CSV
  drivers::LidarSettings lidar_settings;  // the LiDAR family's own section (velodyne:, hesai:)
  FrameCutConfig frame_cut;
  std::optional<ExtrinsicConfig> extrinsic;
  // Resolved through relative_to chains; identity for the body IMU (and for its LiDAR when the
  // body is that LiDAR's internal IMU and no extrinsic is given, which the loader rejects).
  Eigen::Isometry3d T_body_sensor = Eigen::Isometry3d::Identity();
  double time_offset_s = 0.0;  // added once to this sensor's mapped time
  ClockConfig clock;
  int ring_capacity = 0;  // packets / samples / frames; default depends on the sensor kind
  InternalImuConfig imu;
  // LiDARs: this LiDAR's own point settings in the estimator (`lio:`; unset values are
  // estimator.lio's). With several LiDARs the model defaults fill the values the file leaves to
  // them from this LiDAR's own model (apply_estimator_defaults), and name them in lio_from_model.
  estimator::LidarLioParams lio;
  // Keys filled from the model: "dept_err", "beam_err_deg", "point_filter_num", "build_map".
  std::set<std::string> lio_from_model;
  // A sparse spinning LiDAR beside a denser one is matched only (build_map false, in
  // lio_from_model) unless the file sets lio.build_map:
  bool lio_build_map_given = false;
  CameraConfig camera;
  CanConfig can;
  SerialConfig serial;
  DatasetConfig dataset;
  int line = 0;  // where the sensor is defined in the file (for later runtime messages)
};

struct LoggingSection {
  std::string level = "info";  // trace, debug, info, warn, error, critical, off
};

// LCM channel names (docs/lcm.md), before channel_suffix is appended. UPPER_SNAKE.
struct LcmChannelNames {
  std::string pose = "LIVOD_POSE";          // livod.pose_t, one per filter update
  std::string pose_imu = "LIVOD_POSE_IMU";  // livod.pose_t, one per body-IMU sample
  std::string health = "LIVOD_HEALTH";      // livod.health_t, once per health period
  std::string cloud = "LIVOD_CLOUD";        // livod.cloud_t, one per filter update
  std::string bot_core_pose = "POSE_BODY";  // libbot2's bot_core.pose_t
  std::string command = "LIVOD_COMMAND";    // livod.command_t, requests to livod (subscribed)
  std::string command_result = "LIVOD_COMMAND_RESULT";  // livod.command_result_t, the answers
};

struct LcmOutputConfig {
  bool enabled = true;
  // ttl=0: multicast never leaves the host unless the configuration asks for it.
  std::string url = "udpm://239.255.76.67:7667?ttl=0";
  std::string channel_suffix;  // appended to every channel, e.g. "_REPLAY"
  LcmChannelNames channels;
  bool publish_imu_rate = true;
  bool publish_cloud = false;
  int cloud_max_points = 20000;  // LIVOD_CLOUD is decimated to at most this many points
  // bot_core.pose_t on channels.bot_core_pose: the IMU-rate pose when publish_imu_rate is on,
  // else the filter-rate pose.
  bool publish_bot_core_pose = true;

  // Full channel names (suffix appended).
  [[nodiscard]] std::string channel(const std::string& name) const { return name + channel_suffix; }
};

// Map saves on request (SIGUSR1, livod.command_t COMMAND_SAVE_MAP) and at stop, while running
// (docs/deploy.md "Saving the map").
struct MapSavesConfig {
  bool enabled = true;  // the map is accumulated and SIGUSR1 / the LCM command save it
  // Where saves go; empty = the default: $STATE_DIRECTORY/maps under systemd, else OUTDIR/maps for
  // `replay --realtime -o OUTDIR`, else ./maps (the default folder is created; a configured one
  // must exist).
  std::filesystem::path directory;
  // false: every save is a new file (map-<UTC time>-<number>.pcd); true: each save replaces
  // DIRECTORY/map.pcd (atomically).
  bool overwrite = false;
  bool at_stop = false;  // also save one when the daemon stops
};

struct OutputsConfig {
  LcmOutputConfig lcm;
  std::filesystem::path trajectory;     // TUM file; empty = none
  std::filesystem::path map_pcd;        // PCD written at shutdown; empty = none
  std::filesystem::path timing_report;  // per-stage timing; empty = none
  // `livod run` also records its live sensors' raw data into a new subfolder of this folder per
  // start (docs/record.md); empty = no recording.
  std::filesystem::path record;
  MapSavesConfig map_saves;
};

struct HealthConfig {
  double period_s = 1.0;       // LIVOD_HEALTH and sd_notify STATUS= rate
  double stale_after_s = 0.5;  // a stream without data for this long is reported stale
};

// Thread scheduling. 0 = SCHED_OTHER; 1..99 = SCHED_FIFO priority (needs CAP_SYS_NICE or
// LimitRTPRIO in the service).
struct RealtimeConfig {
  int capture_priority = 0;
  int scheduler_priority = 0;
  int capture_cpu = -1;      // pin every capture thread to this CPU; -1 = any
  int scheduler_cpu = -1;    // pin the scheduler thread to this CPU; -1 = any
  bool lock_memory = false;  // mlockall(MCL_CURRENT | MCL_FUTURE)
  // PM QoS CPU wake-up latency bound (us) held while running; -1 = no request
  // (daemon/runtime/cpu_latency_request.hpp).
  int cpu_dma_latency_us = -1;
};

// One estimator setting as the configuration's sensors made it (estimator_defaults.hpp): what
// check-config prints for it.
struct EstimatorChoice {
  std::string key;     // e.g. "lio.point_filter_num"
  std::string value;   // as it would be written in the file
  std::string reason;  // why: the file set it, or the model fact it follows from
};

struct LivodConfig {
  std::filesystem::path source_file;  // the config file; empty when loaded from a string
  std::filesystem::path base_dir;     // relative paths in the file are resolved against it
  LoggingSection logging;
  std::string body_frame;      // "<imu sensor>" or "<lidar>.imu"
  int body_sensor_index = -1;  // index into sensors of the body IMU (or of its LiDAR)
  bool body_is_internal_imu = false;
  std::vector<SensorConfig> sensors;
  estimator::EstimatorParams estimator;  // effective: the file's values, then the model defaults
  // Estimator keys the file set ("lio.point_filter_num", ...): model defaults never change them.
  std::set<std::string> estimator_given;
  std::vector<EstimatorChoice> estimator_choices;  // the model-dependent values and why
  OutputsConfig outputs;
  HealthConfig health;
  RealtimeConfig realtime;

  [[nodiscard]] const SensorConfig* find_sensor(std::string_view name) const;
};

// Names of enum values as they appear in the YAML file.
template <class E>
struct EnumEntry {
  std::string_view name;
  E value;
};

template <class E>
std::span<const EnumEntry<E>> enum_entries();

template <>
std::span<const EnumEntry<Driver>> enum_entries<Driver>();
template <>
std::span<const EnumEntry<SensorKind>> enum_entries<SensorKind>();
template <>
std::span<const EnumEntry<ReplayFormat>> enum_entries<ReplayFormat>();
template <>
std::span<const EnumEntry<FrameCutMode>> enum_entries<FrameCutMode>();
template <>
std::span<const EnumEntry<ClockMode>> enum_entries<ClockMode>();
template <>
std::span<const EnumEntry<CameraModel>> enum_entries<CameraModel>();
template <>
std::span<const EnumEntry<CanDecoder>> enum_entries<CanDecoder>();
template <>
std::span<const EnumEntry<CanQuantity>> enum_entries<CanQuantity>();
template <>
std::span<const EnumEntry<CanUnit>> enum_entries<CanUnit>();
template <>
std::span<const EnumEntry<SerialProtocol>> enum_entries<SerialProtocol>();
template <>
std::span<const EnumEntry<TimeUnit>> enum_entries<TimeUnit>();
template <>
std::span<const EnumEntry<TimeReference>> enum_entries<TimeReference>();
template <>
std::span<const EnumEntry<ScanStamp>> enum_entries<ScanStamp>();

template <class E>
std::string_view enum_name(E value) {
  for (const auto& entry : enum_entries<E>()) {
    if (entry.value == value) return entry.name;
  }
  return "?";
}

template <class E>
std::optional<E> parse_enum(std::string_view name) {
  for (const auto& entry : enum_entries<E>()) {
    if (entry.name == name) return entry.value;
  }
  return std::nullopt;
}

}  // namespace livod::daemon
