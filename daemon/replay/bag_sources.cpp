// One topic of a ROS1 bag: one event per message, stamped with its record time.

#include <fmt/core.h>

#include <algorithm>
#include <cmath>

#include "core/error.hpp"
#include "daemon/replay/cloud_conversion.hpp"
#include "daemon/replay/source_kinds.hpp"
#include "io/rosbag/bag_reader.hpp"

namespace livod::daemon::replay {
namespace {

namespace rb = io::rosbag;

constexpr double kStandardGravity = 9.80665;  // m/s^2 per g

// The cursor over one topic and the message it has read ahead.
class BagTopic {
 public:
  BagTopic(const std::filesystem::path& file, const std::string& topic) : bag_(file) {
    for (const auto& c : bag_.connections()) {
      if (c.topic == topic) {
        type_ = c.type;
        break;
      }
    }
    if (type_.empty()) {
      std::string topics;
      for (const auto& t : bag_.topics()) topics += (topics.empty() ? "" : ", ") + t.topic;
      throw Error(bag_.source() + ": no topic '" + topic + "' (topics: " + topics + ")");
    }
    start_ns_ = bag_.start_time_ns().value_or(0);
    end_ns_ = bag_.end_time_ns().value_or(0);
    rb::BagQuery query;
    query.topics = {topic};
    cursor_.emplace(bag_.read(query));
  }

  [[nodiscard]] const std::string& type() const { return type_; }

  std::optional<std::int64_t> peek_time() {
    if (!pending_ && !ended_) {
      pending_ = cursor_->next();
      ended_ = !pending_;
    }
    if (!pending_) return std::nullopt;
    return pending_->time_ns;
  }

  // The message announced by peek_time(); valid until take() is called again.
  std::optional<rb::BagMessage> take() {
    peek_time();
    auto m = pending_;
    pending_.reset();
    if (m) {
      last_ns_ = m->time_ns;
      ++messages_;
    }
    return m;
  }

  [[nodiscard]] std::optional<double> fraction_done() const {
    if (end_ns_ <= start_ns_) return std::nullopt;
    return static_cast<double>(last_ns_ - start_ns_) / static_cast<double>(end_ns_ - start_ns_);
  }
  [[nodiscard]] std::uint64_t messages() const { return messages_; }

 private:
  rb::BagReader bag_;
  std::string type_;
  std::optional<rb::MessageCursor> cursor_;
  std::optional<rb::BagMessage> pending_;
  bool ended_ = false;
  std::int64_t start_ns_ = 0;
  std::int64_t end_ns_ = 0;
  std::int64_t last_ns_ = 0;
  std::uint64_t messages_ = 0;
};

class BagImuSource final : public ReplaySource {
 public:
  BagImuSource(BagTopic topic, const DatasetConfig& dataset)
      : topic_(std::move(topic)),
        accel_scale_(dataset.accel_unit == CanUnit::g ? kStandardGravity : 1.0),
        gyro_scale_(dataset.gyro_unit == CanUnit::deg_s ? M_PI / 180.0 : 1.0) {}

  std::optional<std::int64_t> peek_time() override { return topic_.peek_time(); }

  void deliver(const drivers::DecoderSinks& sinks) override {
    const auto m = topic_.take();
    if (!m) return;
    m->decode_into(msg_);
    ImuSample s;
    s.stamp.sensor = SensorTime(msg_.header.stamp.to_ns());
    s.stamp.host = HostTime(m->time_ns);
    s.stamp.mapped = MappedTime(m->time_ns);  // until the clock domain maps it
    const auto& w = msg_.angular_velocity;
    const auto& a = msg_.linear_acceleration;
    s.gyro_rad_s = gyro_scale_ * Eigen::Vector3d(w.x, w.y, w.z);
    s.accel_m_s2 = accel_scale_ * Eigen::Vector3d(a.x, a.y, a.z);
    if (!s.gyro_rad_s.allFinite() || !s.accel_m_s2.allFinite()) {
      ++non_finite_;
      return;
    }
    if (sinks.on_imu) sinks.on_imu(s);
  }

  void finish(const drivers::DecoderSinks& /*sinks*/) override {}

  [[nodiscard]] std::string summary() const override {
    return fmt::format("bag sensor_msgs/Imu: messages {}, non-finite samples dropped {}",
                       topic_.messages(), non_finite_);
  }
  [[nodiscard]] std::optional<double> fraction_done() const override {
    return topic_.fraction_done();
  }

 private:
  BagTopic topic_;
  double accel_scale_;
  double gyro_scale_;
  rb::sensor_msgs::Imu msg_;
  std::uint64_t non_finite_ = 0;
};

class BagCloudSource final : public ReplaySource {
 public:
  BagCloudSource(BagTopic topic, const DatasetConfig& dataset)
      : topic_(std::move(topic)),
        dataset_(dataset),
        livox_(topic_.type() == "livox_ros_driver/CustomMsg") {}

  std::optional<std::int64_t> peek_time() override { return topic_.peek_time(); }

  void deliver(const drivers::DecoderSinks& sinks) override {
    const auto m = topic_.take();
    if (!m) return;
    bool ok = false;
    if (livox_) {
      m->decode_into(livox_msg_);
      ok = custom_msg_to_scan(livox_msg_, scan_, stats_);
    } else {
      m->decode_into(cloud_msg_);
      ok = point_cloud_to_scan(cloud_msg_, dataset_, scratch_, scan_, stats_);
    }
    if (!ok) return;
    scan_.sequence = sequence_++;
    // A recorder receives a scan once it is complete: back-date the record time to the scan
    // start, as packet decoders stamp scans with the receive time of their first packet.
    std::int32_t last = 0;
    for (const auto t : scan_.t_offset_ns) last = std::max(last, t);
    scan_.start.host = HostTime(m->time_ns - last);
    scan_.start.mapped = MappedTime(scan_.start.host.ns);
    if (sinks.on_scan) sinks.on_scan(scan_);
  }

  void finish(const drivers::DecoderSinks& /*sinks*/) override {}

  [[nodiscard]] std::string summary() const override {
    return fmt::format(
        "bag {}: messages {} ({} empty), points {} ({} invalid), dropped beyond 2.1 s {}",
        topic_.type(), stats_.messages, stats_.empty_messages, stats_.points, stats_.invalid_points,
        stats_.dropped_points);
  }
  [[nodiscard]] std::optional<double> fraction_done() const override {
    return topic_.fraction_done();
  }

 private:
  BagTopic topic_;
  DatasetConfig dataset_;
  bool livox_;
  rb::livox_ros_driver::CustomMsg livox_msg_;
  rb::sensor_msgs::PointCloud2 cloud_msg_;
  std::vector<rb::CloudPoint> scratch_;
  LidarScan scan_;
  std::uint32_t sequence_ = 0;
  CloudConversionStats stats_;
};

// Raw sensor packets recorded by a ROS driver (ouster_ros/PacketMsg) through the packet decoder.
class BagPacketSource final : public ReplaySource {
 public:
  BagPacketSource(BagTopic topic, std::unique_ptr<drivers::LidarDecoder> decoder)
      : topic_(std::move(topic)), decoder_(std::move(decoder)) {}

  std::optional<std::int64_t> peek_time() override { return topic_.peek_time(); }

  void deliver(const drivers::DecoderSinks& sinks) override {
    const auto m = topic_.take();
    if (!m) return;
    m->decode_into(msg_);
    const std::span<const std::byte> payload(reinterpret_cast<const std::byte*>(msg_.buf.data()),
                                             msg_.buf.size());
    // The recorded message has no UDP port; decoders that share a port tell packets by size.
    decoder_->on_packet({payload, m->time_ns, 0}, sinks);
  }

  void finish(const drivers::DecoderSinks& sinks) override { decoder_->flush(sinks); }

  [[nodiscard]] std::string summary() const override {
    const auto& c = decoder_->counters();
    return fmt::format(
        "bag ouster_ros/PacketMsg: messages {}; {}: packets {} (lidar {}, imu {}), scans {} ({} "
        "incomplete), points {}, sequence gaps {}, decode errors {}",
        topic_.messages(), decoder_->model_name(), c.packets, c.lidar_packets, c.imu_packets,
        c.scans, c.incomplete_scans, c.points, c.sequence_gaps, c.decode_errors);
  }
  [[nodiscard]] std::optional<double> fraction_done() const override {
    return topic_.fraction_done();
  }

 private:
  BagTopic topic_;
  std::unique_ptr<drivers::LidarDecoder> decoder_;
  rb::ouster_ros::PacketMsg msg_;
};

}  // namespace

std::unique_ptr<ReplaySource> make_bag_source(const std::filesystem::path& file,
                                              const std::string& topic, const SensorConfig& sensor,
                                              std::unique_ptr<drivers::LidarDecoder> decoder) {
  BagTopic cursor(file, topic);
  const std::string type = cursor.type();
  const SensorKind kind = sensor_kind(sensor.driver);
  const std::string where = "sensor '" + sensor.name + "', topic '" + topic + "' (" + type + ")";
  if (type == "sensor_msgs/Imu") {
    if (kind != SensorKind::imu)
      throw Error(where + ": IMU messages for a " + std::string(enum_name(kind)));
    return std::make_unique<BagImuSource>(std::move(cursor), sensor.dataset);
  }
  if (type == "sensor_msgs/PointCloud2" || type == "livox_ros_driver/CustomMsg") {
    if (kind != SensorKind::lidar)
      throw Error(where + ": point clouds for a " + std::string(enum_name(kind)));
    return std::make_unique<BagCloudSource>(std::move(cursor), sensor.dataset);
  }
  if (type == "ouster_ros/PacketMsg") {
    if (!decoder) throw Error(where + ": raw packets need a packet LiDAR driver (ouster)");
    return std::make_unique<BagPacketSource>(std::move(cursor), std::move(decoder));
  }
  throw Error(where +
              ": replay reads sensor_msgs/Imu, sensor_msgs/PointCloud2, "
              "livox_ros_driver/CustomMsg and ouster_ros/PacketMsg topics");
}

}  // namespace livod::daemon::replay
