// One topic of a ROS1 bag: one event per message, stamped with its record time.

#include <fmt/core.h>

#include <algorithm>
#include <cmath>

#include "core/error.hpp"
#include "core/units.hpp"
#include "daemon/replay/cloud_conversion.hpp"
#include "daemon/replay/source_kinds.hpp"
#include "io/rosbag/bag_reader.hpp"

namespace livod::daemon::replay {
namespace {

namespace rb = io::rosbag;

// The cursor over one topic and the message it has read ahead.
class BagTopic {
 public:
  // The bag is read with recovery: a missing index is rebuilt, damage is read past and reported.
  BagTopic(const std::filesystem::path& file, const std::string& topic)
      : bag_(file, rb::BagReader::Options{.recover = true}) {
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
  [[nodiscard]] const std::string& file() const { return bag_.source(); }

  [[nodiscard]] io::InputLossLog losses() const {
    io::InputLossLog log = bag_.losses();
    if (cursor_) log.merge(cursor_->losses());
    return log;
  }
  [[nodiscard]] std::vector<std::string> notes() const {
    if (!bag_.recovered()) return {};
    return {bag_.source() + ": the bag index is missing or broken (" + bag_.index_problem() +
            "): it was rebuilt by scanning the chunks, as rosbag reindex does"};
  }

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

// livox_ros_driver2 (Mid-360, HAP) publishes the same CustomMsg under its own package name: the
// same definition, so the same md5, and the same bytes.
constexpr std::string_view kLivoxDriver2CustomMsg = "livox_ros_driver2/CustomMsg";

bool is_livox_custom_msg(std::string_view type) {
  return type == rb::MessageTraits<rb::livox_ros_driver::CustomMsg>::type ||
         type == kLivoxDriver2CustomMsg;
}

void decode_custom_msg(const rb::BagMessage& m, rb::livox_ros_driver::CustomMsg& out) {
  if (m.connection != nullptr && m.connection->type == kLivoxDriver2CustomMsg) {
    const auto md5 = rb::MessageTraits<rb::livox_ros_driver::CustomMsg>::md5sum;
    if (m.connection->md5sum != md5 && m.connection->md5sum != "*") {
      throw Error("topic " + m.connection->topic + ": livox_ros_driver2/CustomMsg with md5 " +
                  m.connection->md5sum + ", not livox_ros_driver's " + std::string(md5));
    }
    rb::deserialize(m.data, out);
    return;
  }
  m.decode_into(out);
}

// Malformed messages of a topic are counted and skipped, so that one corrupt message loses one
// measurement. A topic whose first messages all fail is a configuration problem (a wrong time
// field, a topic of another layout): that stops the replay with the first error.
class MalformedMessages {
 public:
  MalformedMessages(std::string where, std::string file)
      : where_(std::move(where)), file_(std::move(file)) {}

  void ok() { ++ok_; }
  void failed(const std::exception& e, std::int64_t time_ns) {
    io::InputLoss loss;
    loss.file = file_;
    loss.records = 1;
    loss.unit = "messages";
    loss.reason = fmt::format("{}: the message recorded at {:.6f} s does not decode: {}", where_,
                              static_cast<double>(time_ns) * 1e-9, e.what());
    losses_.add(std::move(loss));
    if (count_++ == 0) first_ = e.what();
    if (ok_ == 0 && count_ >= kGiveUpAfter) {
      throw Error(where_ + ": the first " + std::to_string(count_) +
                  " messages cannot be read: " + first_);
    }
  }
  [[nodiscard]] std::uint64_t count() const { return count_; }
  [[nodiscard]] const io::InputLossLog& losses() const { return losses_; }

 private:
  static constexpr std::uint64_t kGiveUpAfter = 5;
  std::string where_;
  std::string file_;
  io::InputLossLog losses_;
  std::string first_;
  std::uint64_t ok_ = 0;
  std::uint64_t count_ = 0;
};

// What every bag topic source shares: the cursor, the malformed-message policy and reading the
// next message through a decoder that may throw FormatError.
class BagTopicSource : public ReplaySource {
 public:
  BagTopicSource(BagTopic topic, std::string where)
      : topic_(std::move(topic)), malformed_(std::move(where), topic_.file()) {}

  std::optional<std::int64_t> peek_time() override { return topic_.peek_time(); }
  void finish(const drivers::DecoderSinks& /*sinks*/) override {}
  [[nodiscard]] std::optional<double> fraction_done() const override {
    return topic_.fraction_done();
  }
  [[nodiscard]] io::InputLossLog input_losses() const override {
    io::InputLossLog log = topic_.losses();
    log.merge(malformed_.losses());
    return log;
  }
  [[nodiscard]] std::vector<std::string> notes() const override { return topic_.notes(); }

 protected:
  // The next message, once `decode(message)` has read it; nullopt at the end or when the message
  // is malformed (counted, skipped).
  template <class Decode>
  std::optional<rb::BagMessage> take(Decode&& decode) {
    auto m = topic_.take();
    if (!m) return std::nullopt;
    try {
      decode(*m);
    } catch (const FormatError& e) {
      malformed_.failed(e, m->time_ns);
      return std::nullopt;
    }
    malformed_.ok();
    return m;
  }

  BagTopic topic_;
  MalformedMessages malformed_;
};

class BagImuSource final : public BagTopicSource {
 public:
  BagImuSource(BagTopic topic, const DatasetConfig& dataset, std::string where)
      : BagTopicSource(std::move(topic), std::move(where)),
        accel_scale_(dataset.accel_unit == CanUnit::g ? kStandardGravity : 1.0),
        gyro_scale_(dataset.gyro_unit == CanUnit::deg_s ? M_PI / 180.0 : 1.0) {}

  void deliver(const drivers::DecoderSinks& sinks) override {
    const auto m = take([this](const rb::BagMessage& message) { message.decode_into(msg_); });
    if (!m) return;
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

  [[nodiscard]] std::string summary() const override {
    return fmt::format(
        "bag sensor_msgs/Imu: messages {}, malformed {}, non-finite samples dropped {}",
        topic_.messages(), malformed_.count(), non_finite_);
  }

 private:
  double accel_scale_;
  double gyro_scale_;
  rb::sensor_msgs::Imu msg_;
  std::uint64_t non_finite_ = 0;
};

class BagCloudSource final : public BagTopicSource {
 public:
  BagCloudSource(BagTopic topic, const DatasetConfig& dataset, std::string where)
      : BagTopicSource(std::move(topic), std::move(where)),
        dataset_(dataset),
        livox_(is_livox_custom_msg(topic_.type())) {}

  void deliver(const drivers::DecoderSinks& sinks) override {
    bool ok = false;
    const auto m = take([&](const rb::BagMessage& message) {
      if (livox_) {
        decode_custom_msg(message, livox_msg_);
        ok = custom_msg_to_scan(livox_msg_, scan_, stats_);
      } else {
        message.decode_into(cloud_msg_);
        ok = point_cloud_to_scan(cloud_msg_, dataset_, scratch_, scan_, stats_);
      }
    });
    if (!m || !ok) return;
    scan_.sequence = sequence_++;
    // A recorder receives a scan once it is complete: back-date the record time to the scan
    // start, as packet decoders stamp scans with the receive time of their first packet.
    scan_.start.host = HostTime(m->time_ns - scan_.span_ns());
    scan_.start.mapped = MappedTime(scan_.start.host.ns);
    if (sinks.on_scan) sinks.on_scan(scan_);
  }

  [[nodiscard]] std::string summary() const override {
    return fmt::format(
        "bag {}: messages {} ({} empty, {} malformed, {} with unusable times), points {} ({} "
        "invalid), dropped (beyond 2.1 s or no time) {}",
        topic_.type(), topic_.messages(), stats_.empty_messages, malformed_.count(),
        stats_.bad_time_messages, stats_.points, stats_.invalid_points, stats_.dropped_points);
  }

 private:
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
class BagPacketSource final : public BagTopicSource {
 public:
  BagPacketSource(BagTopic topic, std::unique_ptr<drivers::LidarDecoder> decoder, std::string where)
      : BagTopicSource(std::move(topic), std::move(where)), decoder_(std::move(decoder)) {}

  void deliver(const drivers::DecoderSinks& sinks) override {
    const auto m = take([this](const rb::BagMessage& message) { message.decode_into(msg_); });
    if (!m) return;
    const std::span<const std::byte> payload(reinterpret_cast<const std::byte*>(msg_.buf.data()),
                                             msg_.buf.size());
    // The recorded message has no UDP port; decoders that share a port tell packets by size.
    decoder_->on_packet({payload, m->time_ns, 0}, sinks);
  }

  void finish(const drivers::DecoderSinks& sinks) override { decoder_->flush(sinks); }

  [[nodiscard]] std::string summary() const override {
    const auto& c = decoder_->counters();
    return fmt::format(
        "bag ouster_ros/PacketMsg: messages {} ({} malformed); {}: packets {} (lidar {}, imu {}), "
        "scans {} ({} incomplete), points {}, sequence gaps {}, decode errors {}",
        topic_.messages(), malformed_.count(), decoder_->model_name(), c.packets, c.lidar_packets,
        c.imu_packets, c.scans, c.incomplete_scans, c.points, c.sequence_gaps, c.decode_errors);
  }

 private:
  std::unique_ptr<drivers::LidarDecoder> decoder_;
  rb::ouster_ros::PacketMsg msg_;
};

}  // namespace

drivers::ouster::SensorMetadata bag_ouster_metadata(const std::filesystem::path& file,
                                                    const std::string& packet_topic) {
  const rb::BagReader bag(file, rb::BagReader::Options{.recover = true});
  const std::string sibling = packet_topic.substr(0, packet_topic.rfind('/') + 1) + "metadata";
  const auto is_string = [](const rb::TopicInfo& t) {
    return t.type == rb::MessageTraits<rb::std_msgs::String>::type;
  };
  std::vector<std::string> candidates;
  for (const auto& t : bag.topics()) {
    if (!is_string(t)) continue;
    if (t.topic == sibling) {
      candidates = {t.topic};
      break;
    }
    if (t.topic.size() >= 8 && t.topic.ends_with("metadata")) candidates.push_back(t.topic);
  }
  if (candidates.size() != 1) {
    throw Error(bag.source() + ": no 'metadata' given and the bag has " +
                (candidates.empty() ? std::string("no std_msgs/String metadata topic")
                                    : "several metadata topics") +
                " (expected " + sibling + "); give the sensor's metadata JSON ('metadata')");
  }
  rb::BagQuery query;
  query.topics = candidates;
  auto cursor = bag.read(query);
  const auto message = cursor.next();
  if (!message) {
    io::InputLossLog losses = bag.losses();
    losses.merge(cursor.losses());
    throw Error(bag.source() + ": topic " + candidates[0] + " has no message" +
                (losses.empty()
                     ? std::string()
                     : " (the bag is damaged: " + io::format_loss(losses.entries()[0]) + ")"));
  }
  const auto text = message->as<rb::std_msgs::String>();
  return drivers::ouster::parse_metadata(text.data, bag.source() + " topic " + candidates[0]);
}

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
    return std::make_unique<BagImuSource>(std::move(cursor), sensor.dataset, where);
  }
  if (type == "sensor_msgs/PointCloud2" || is_livox_custom_msg(type)) {
    if (kind != SensorKind::lidar)
      throw Error(where + ": point clouds for a " + std::string(enum_name(kind)));
    return std::make_unique<BagCloudSource>(std::move(cursor), sensor.dataset, where);
  }
  if (type == "ouster_ros/PacketMsg") {
    if (!decoder) throw Error(where + ": raw packets need a packet LiDAR driver (ouster)");
    return std::make_unique<BagPacketSource>(std::move(cursor), std::move(decoder), where);
  }
  throw Error(where +
              ": replay reads sensor_msgs/Imu, sensor_msgs/PointCloud2, "
              "livox_ros_driver/CustomMsg, livox_ros_driver2/CustomMsg and ouster_ros/PacketMsg "
              "topics");
}

}  // namespace livod::daemon::replay
