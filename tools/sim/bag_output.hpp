#pragma once
// The simulated sequence as a ROS1 bag, for ROS-based peers (FAST-LIVO2, FAST-LIO2) to run on the
// same data as livod. The bag is a transcoding of the output folder, not a second simulation: each
// capture is read back and decoded with livod's own decoders (pcap -> LidarDecoder, candump log ->
// SbgCanDecoder, EuRoC folder -> PNG), so the bag holds exactly what livod decodes from the files.
//
// Topics (the ROS conventions the peers' shipped configs use; a second sensor of the same kind gets
// /<sensor name>/... instead):
//   Livox LiDAR       /livox/lidar            livox_ros_driver/CustomMsg, one per decoder scan
//   Livox IMU         /livox/imu              sensor_msgs/Imu
//   Ouster LiDAR      /os_cloud_node/points   sensor_msgs/PointCloud2 (x y z intensity t ring)
//   Ouster IMU        /os_cloud_node/imu      sensor_msgs/Imu
//   Velodyne LiDAR    /velodyne_points        sensor_msgs/PointCloud2 (x y z intensity t ring time)
//   HDL-32E IMU       /imu/data               sensor_msgs/Imu (from the position packets)
//   CAN IMU           /imu                    sensor_msgs/Imu
//   camera            /left_camera/image      sensor_msgs/Image mono8
//
// Stamps: header stamps are time-synchronised, i.e. every sensor clock is already mapped onto the
// host clock exactly (the inverse of the simulated sensor clock: offset, skew and reset; stamp
// jitter stays in), like a ROS driver on a PTP-synchronised sensor. They share the timeline of
// groundtruth.txt and the camera csv. Record times are when the host had the message: the pcap /
// candump receive time of the datagram or frame that completed it (cameras: the header stamp).
// IMU data is SI (rad/s, m/s^2) as livod decodes it; FAST-LIO/FAST-LIVO2 rescale the accelerometer
// by 9.81 / |mean acc at init|, so SI and the Livox driver's g both work.

#include <cstdint>
#include <filesystem>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "core/measurement.hpp"
#include "drivers/lidar_decoder.hpp"
#include "io/euroc.hpp"
#include "io/rosbag/bag_writer.hpp"
#include "io/rosbag/ros_messages.hpp"
#include "tools/sim/scenario.hpp"
#include "tools/sim/sensor_clock.hpp"

namespace livod::sim {

// Maps a simulated sensor's clock readings back onto the host clock: exactly the inverse of
// SensorClock without its jitter. host_epoch_ns is the host clock at scenario time 0. Some wire
// formats carry the reading only modulo a period (`wrap_ns`, 0 = none): the Velodyne's
// microseconds past the hour, whose hour the decoder takes from the receive time, and the SBG's
// 32-bit microsecond counter; the period count is then the one that fits the receive time.
class SensorClockInverse {
 public:
  SensorClockInverse(const ClockFaults& faults, std::int64_t host_epoch_ns,
                     std::int64_t wrap_ns = 0)
      : faults_(faults), host_epoch_ns_(host_epoch_ns), wrap_ns_(wrap_ns) {}

  // Scenario time (s) of a sensor reading received at host time `rx_ns`. Of the times the
  // reading can mean (several around a clock reset or with a wrapping stamp), the latest one
  // not after the receive time.
  [[nodiscard]] double scenario_time(std::int64_t sensor_ns, std::int64_t rx_ns) const;

  // Host clock (ns) of a sensor reading.
  [[nodiscard]] std::int64_t host_ns(std::int64_t sensor_ns, std::int64_t rx_ns) const;

 private:
  ClockFaults faults_;
  std::int64_t host_epoch_ns_;
  std::int64_t wrap_ns_;
};

// The period after which a model's sensor stamps wrap on the wire (see SensorClockInverse).
std::int64_t lidar_stamp_wrap_ns(const std::string& model);
constexpr std::int64_t kSbgCounterWrapNs = (std::int64_t{1} << 32) * 1000;

// Per-point field layouts of the PointCloud2 LiDARs.
enum class CloudLayout {
  kOuster,    // x y z intensity (float32), t (uint32 ns from the stamp), ring (uint8)
  kVelodyne,  // x y z intensity (float32), t (uint32 ns), ring (uint16), time (float32 s)
};

// Per-point offsets are unsigned on the wire, so the header stamp is the scan start, or its
// earliest valid point if one precedes the start (never for livod's decoders, but not assumed).
// `start_host_ns` is scan.start on the host clock; offsets stay in the decoder's units (ns).

// The valid points of `scan` as a CustomMsg; timebase = the header stamp.
io::rosbag::livox_ros_driver::CustomMsg to_custom_msg(const LidarScan& scan,
                                                      std::int64_t start_host_ns,
                                                      const std::string& frame_id,
                                                      std::uint32_t seq);

// The valid points of `scan` as an unorganised (height 1), dense PointCloud2.
io::rosbag::sensor_msgs::PointCloud2 to_point_cloud2(const LidarScan& scan, CloudLayout layout,
                                                     std::int64_t start_host_ns,
                                                     const std::string& frame_id,
                                                     std::uint32_t seq);

// Orientation unknown (orientation_covariance[0] = -1, REP 145), covariances otherwise zero.
io::rosbag::sensor_msgs::Imu to_imu_msg(const ImuSample& sample, std::int64_t stamp_ns,
                                        const std::string& frame_id, std::uint32_t seq);

// One frame of a EuRoC camera folder (decoded with io/euroc_image.hpp) as a mono8 Image stamped
// with its csv timestamp.
io::rosbag::sensor_msgs::Image load_image_message(const io::EurocImageRecord& record,
                                                  const std::string& frame_id, std::uint32_t seq);

// livod's decoder for a simulated model's capture, from the model's family
// (drivers/lidar_family.hpp); `decoder_file` is the file the simulator wrote beside the capture
// for it (Ouster metadata JSON, Hesai angle correction CSV), passed as the family takes it.
std::unique_ptr<drivers::LidarDecoder> make_capture_decoder(
    const std::string& model, const std::optional<std::filesystem::path>& decoder_file);

// What the bag is made of: the files of one runner output folder.
struct BagLidarSource {
  std::string name;   // sensor name (frame_id, topic prefix when the default topic is taken)
  std::string model;  // simulated model (AVIA, MID-360, OS1-64, VLP-16, ...)
  std::filesystem::path capture;                      // <name>.pcap
  std::optional<std::filesystem::path> decoder_file;  // Ouster metadata, Hesai angle CSV
  ClockFaults clock;
  bool imu = true;  // write the internal IMU (when the model has one)
};

struct BagCanImuSource {
  std::string name;
  std::filesystem::path log;  // candump log
  ClockFaults clock;          // of the device's microsecond counter (SBG)
  CanImuFormat format = CanImuFormat::kSbg;
};

struct BagCameraSource {
  std::string name;
  std::filesystem::path folder;  // mav0/<name> (data.csv, data/*.png)
};

struct SequenceBagSpec {
  std::vector<BagLidarSource> lidars;
  std::optional<BagCanImuSource> can_imu;
  std::vector<BagCameraSource> cameras;
  std::int64_t host_epoch_ns = 0;  // host clock at scenario time 0
  io::rosbag::Compression compression = io::rosbag::Compression::kLz4;
};

struct BagTopicReport {
  std::string topic;
  std::string type;
  std::uint64_t messages = 0;
};

struct SequenceBagReport {
  std::vector<BagTopicReport> topics;
  // Camera frames listed in data.csv whose PNG is absent (a run with --no-images): not in the bag.
  std::uint64_t missing_images = 0;
};

// Writes the bag (truncating `bag`). Messages are merged in record-time order across sensors, so
// the file plays like a recording and memory stays bounded (one scan and one image at a time).
// Throws livod::Error / livod::FormatError when a source file is unreadable or malformed.
SequenceBagReport write_sequence_bag(const std::filesystem::path& bag, const SequenceBagSpec& spec);

}  // namespace livod::sim
