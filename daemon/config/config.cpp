#include "daemon/config/config.hpp"

#include <array>

namespace livod::daemon {

SensorKind sensor_kind(Driver driver) {
  switch (driver) {
    case Driver::ouster:
    case Driver::velodyne:
    case Driver::livox_sdk1:
    case Driver::livox_sdk2:
    case Driver::hesai:
    case Driver::dataset_lidar:
      return SensorKind::lidar;
    case Driver::v4l2:
    case Driver::aravis:
    case Driver::dataset_camera:
      return SensorKind::camera;
    case Driver::can_imu:
    case Driver::serial_imu:
    case Driver::dataset_imu:
      return SensorKind::imu;
  }
  return SensorKind::lidar;
}

bool is_packet_lidar(Driver driver) {
  return drivers::find_family(enum_name(driver)) != nullptr;
}

const SensorConfig* LivodConfig::find_sensor(std::string_view name) const {
  for (const auto& sensor : sensors) {
    if (sensor.name == name) return &sensor;
  }
  return nullptr;
}

namespace {

constexpr std::array<EnumEntry<Driver>, 12> kDrivers{{
    {"ouster", Driver::ouster},
    {"velodyne", Driver::velodyne},
    {"livox_sdk1", Driver::livox_sdk1},
    {"livox_sdk2", Driver::livox_sdk2},
    {"hesai", Driver::hesai},
    {"v4l2", Driver::v4l2},
    {"aravis", Driver::aravis},
    {"can_imu", Driver::can_imu},
    {"serial_imu", Driver::serial_imu},
    {"dataset_lidar", Driver::dataset_lidar},
    {"dataset_imu", Driver::dataset_imu},
    {"dataset_camera", Driver::dataset_camera},
}};
constexpr std::array<EnumEntry<SensorKind>, 3> kSensorKinds{{
    {"lidar", SensorKind::lidar},
    {"camera", SensorKind::camera},
    {"imu", SensorKind::imu},
}};
constexpr std::array<EnumEntry<ReplayFormat>, 4> kReplayFormats{{
    {"pcap", ReplayFormat::pcap},
    {"candump", ReplayFormat::candump},
    {"rosbag1", ReplayFormat::rosbag1},
    {"euroc", ReplayFormat::euroc},
}};
constexpr std::array<EnumEntry<FrameCutMode>, 3> kFrameCutModes{{
    {"azimuth", FrameCutMode::azimuth},
    {"time", FrameCutMode::time},
    {"frame_id", FrameCutMode::frame_id},
}};
constexpr std::array<EnumEntry<ClockMode>, 4> kClockModes{{
    {"auto", ClockMode::automatic},
    {"direct", ClockMode::direct},
    {"free_running", ClockMode::free_running},
    {"receive_time", ClockMode::receive_time},
}};
constexpr std::array<EnumEntry<CameraModel>, 2> kCameraModels{{
    {"pinhole", CameraModel::pinhole},
    {"equidistant", CameraModel::equidistant},
}};
constexpr std::array<EnumEntry<CanDecoder>, 3> kCanDecoders{{
    {"bosch_mm7", CanDecoder::bosch_mm7},
    {"sbg", CanDecoder::sbg},
    {"custom", CanDecoder::custom},
}};
constexpr std::array<EnumEntry<CanQuantity>, 6> kCanQuantities{{
    {"accel_x", CanQuantity::accel_x},
    {"accel_y", CanQuantity::accel_y},
    {"accel_z", CanQuantity::accel_z},
    {"gyro_x", CanQuantity::gyro_x},
    {"gyro_y", CanQuantity::gyro_y},
    {"gyro_z", CanQuantity::gyro_z},
}};
constexpr std::array<EnumEntry<CanUnit>, 4> kCanUnits{{
    {"m_s2", CanUnit::m_s2},
    {"g", CanUnit::g},
    {"rad_s", CanUnit::rad_s},
    {"deg_s", CanUnit::deg_s},
}};
constexpr std::array<EnumEntry<SerialProtocol>, 2> kSerialProtocols{{
    {"xsens_mtdata2", SerialProtocol::xsens_mtdata2},
    {"vectornav_binary", SerialProtocol::vectornav_binary},
}};
constexpr std::array<EnumEntry<TimeUnit>, 4> kTimeUnits{{
    {"ns", TimeUnit::ns},
    {"us", TimeUnit::us},
    {"ms", TimeUnit::ms},
    {"s", TimeUnit::s},
}};
constexpr std::array<EnumEntry<TimeReference>, 2> kTimeReferences{{
    {"relative", TimeReference::relative},
    {"absolute", TimeReference::absolute},
}};
constexpr std::array<EnumEntry<ScanStamp>, 2> kScanStamps{{
    {"start", ScanStamp::start},
    {"end", ScanStamp::end},
}};

}  // namespace

template <>
std::span<const EnumEntry<Driver>> enum_entries<Driver>() {
  return kDrivers;
}
template <>
std::span<const EnumEntry<SensorKind>> enum_entries<SensorKind>() {
  return kSensorKinds;
}
template <>
std::span<const EnumEntry<ReplayFormat>> enum_entries<ReplayFormat>() {
  return kReplayFormats;
}
template <>
std::span<const EnumEntry<FrameCutMode>> enum_entries<FrameCutMode>() {
  return kFrameCutModes;
}
template <>
std::span<const EnumEntry<ClockMode>> enum_entries<ClockMode>() {
  return kClockModes;
}
template <>
std::span<const EnumEntry<CameraModel>> enum_entries<CameraModel>() {
  return kCameraModels;
}
template <>
std::span<const EnumEntry<CanDecoder>> enum_entries<CanDecoder>() {
  return kCanDecoders;
}
template <>
std::span<const EnumEntry<CanQuantity>> enum_entries<CanQuantity>() {
  return kCanQuantities;
}
template <>
std::span<const EnumEntry<CanUnit>> enum_entries<CanUnit>() {
  return kCanUnits;
}
template <>
std::span<const EnumEntry<SerialProtocol>> enum_entries<SerialProtocol>() {
  return kSerialProtocols;
}
template <>
std::span<const EnumEntry<TimeUnit>> enum_entries<TimeUnit>() {
  return kTimeUnits;
}
template <>
std::span<const EnumEntry<TimeReference>> enum_entries<TimeReference>() {
  return kTimeReferences;
}
template <>
std::span<const EnumEntry<ScanStamp>> enum_entries<ScanStamp>() {
  return kScanStamps;
}

}  // namespace livod::daemon
