#include "tools/sim/bag_output.hpp"

#include <algorithm>
#include <bit>
#include <cmath>
#include <cstring>
#include <deque>
#include <limits>
#include <memory>
#include <opencv2/core/mat.hpp>
#include <set>

#include "core/error.hpp"
#include "drivers/imu/bosch_mm7.hpp"
#include "drivers/imu/candump_frames.hpp"
#include "drivers/imu/sbg_can.hpp"
#include "drivers/lidar_family.hpp"
#include "drivers/livox/livox_decoder.hpp"
#include "io/candump.hpp"
#include "io/euroc.hpp"
#include "io/euroc_image.hpp"
#include "io/pcap.hpp"
#include "tools/sim/lidar_registry.hpp"

namespace livod::sim {
namespace {

namespace ros = io::rosbag;

ros::RosTime ros_time(std::int64_t ns) {
  return ros::RosTime::from_ns(ns);
}

// The earliest valid point's offset when it precedes the scan start, else 0.
std::int64_t stamp_shift_ns(const LidarScan& scan) {
  std::int64_t shift = 0;
  for (std::size_t i = 0; i < scan.size(); ++i) {
    if (scan.valid[i] != 0) shift = std::min<std::int64_t>(shift, scan.t_offset_ns[i]);
  }
  return shift;
}

std::size_t valid_count(const LidarScan& scan) {
  return static_cast<std::size_t>(std::count(scan.valid.begin(), scan.valid.end(), 1));
}

template <class T>
void put(std::vector<std::uint8_t>& data, std::size_t offset, T value) {
  // PointCloud2 data is little-endian (is_bigendian = false), as is every host livod runs on.
  static_assert(std::endian::native == std::endian::little);
  std::memcpy(data.data() + offset, &value, sizeof(T));
}

// ---- message sources merged by record time -----------------------------------------------------

struct PendingMessage {
  std::int64_t record_ns = 0;
  std::uint32_t connection = 0;
  std::vector<std::byte> bytes;
};

class MessageSource {
 public:
  virtual ~MessageSource() = default;
  // Record time of the next message; nullopt once the source is exhausted.
  virtual std::optional<std::int64_t> peek() = 0;
  // Writes the message peek() announced.
  virtual void write_next(ros::BagWriter& bag) = 0;
};

// Messages a decoder produced from one input unit wait here until merged.
class QueuedSource : public MessageSource {
 public:
  std::optional<std::int64_t> peek() override {
    while (queue_.empty() && refill()) {
    }
    if (queue_.empty()) return std::nullopt;
    return queue_.front().record_ns;
  }
  void write_next(ros::BagWriter& bag) override {
    const PendingMessage& m = queue_.front();
    bag.write(m.connection, m.record_ns, std::span<const std::byte>(m.bytes));
    queue_.pop_front();
  }

 protected:
  // Consumes one unit of input (a datagram, a CAN frame, a csv row), which may queue messages;
  // false once the input is exhausted.
  virtual bool refill() = 0;

  template <class Msg>
  void enqueue(std::int64_t record_ns, std::uint32_t connection, const Msg& msg) {
    PendingMessage m;
    m.record_ns = record_ns;
    m.connection = connection;
    ros::serialize(msg, m.bytes);
    queue_.push_back(std::move(m));
  }

 private:
  std::deque<PendingMessage> queue_;
};

struct Topic {
  std::uint32_t connection = 0;
  std::uint64_t* count = nullptr;  // messages written, in the report
};

std::string_view driver_of(const std::string& model) {
  const auto match = drivers::find_model(model);
  return match ? match->family->driver : std::string_view();
}

bool is_livox(const std::string& model) {
  const std::string_view driver = driver_of(model);
  return driver == "livox_sdk1" || driver == "livox_sdk2";
}

bool is_ouster(const std::string& model) {
  return driver_of(model) == "ouster";
}

bool is_hesai(const std::string& model) {
  return driver_of(model) == "hesai";
}

class LidarSource final : public QueuedSource {
 public:
  LidarSource(const BagLidarSource& source, std::int64_t host_epoch_ns, Topic points,
              std::optional<Topic> imu)
      : source_(source),
        clock_(source.clock, host_epoch_ns, lidar_stamp_wrap_ns(source.model)),
        reader_(source.capture),
        decoder_(make_capture_decoder(source.model, source.decoder_file)),
        points_(points),
        imu_(imu),
        livox_(is_livox(source.model)),
        layout_(is_ouster(source.model) ? CloudLayout::kOuster : CloudLayout::kVelodyne) {
    sinks_.on_scan = [this](const LidarScan& scan) { on_scan(scan); };
    sinks_.on_imu = [this](const ImuSample& sample) { on_imu(sample); };
  }

 private:
  bool refill() override {
    if (finished_) return false;
    if (const auto d = reader_.next()) {
      packet_time_ns_ = d->capture_time_ns;
      decoder_->on_packet({d->payload, d->capture_time_ns, d->dst_port}, sinks_);
      return true;
    }
    decoder_->flush(sinks_);
    finished_ = true;
    return true;
  }

  void on_scan(const LidarScan& scan) {
    if (valid_count(scan) == 0) return;
    const std::int64_t start = clock_.host_ns(scan.start.sensor.ns, scan.start.host.ns);
    const std::string& frame = source_.name;
    if (livox_) {
      enqueue(packet_time_ns_, points_.connection, to_custom_msg(scan, start, frame, scan_seq_));
    } else {
      enqueue(packet_time_ns_, points_.connection,
              to_point_cloud2(scan, layout_, start, frame, scan_seq_));
    }
    ++scan_seq_;
    ++*points_.count;
  }

  void on_imu(const ImuSample& sample) {
    if (!imu_) return;
    const std::int64_t stamp = clock_.host_ns(sample.stamp.sensor.ns, sample.stamp.host.ns);
    enqueue(packet_time_ns_, imu_->connection,
            to_imu_msg(sample, stamp, source_.name + "_imu", imu_seq_));
    ++imu_seq_;
    ++*imu_->count;
  }

  BagLidarSource source_;
  SensorClockInverse clock_;
  io::PcapReader reader_;
  std::unique_ptr<drivers::LidarDecoder> decoder_;
  drivers::DecoderSinks sinks_;
  Topic points_;
  std::optional<Topic> imu_;
  bool livox_;
  CloudLayout layout_;
  std::int64_t packet_time_ns_ = 0;
  bool finished_ = false;
  std::uint32_t scan_seq_ = 0;
  std::uint32_t imu_seq_ = 0;
};

class CanImuSource final : public QueuedSource {
 public:
  CanImuSource(const BagCanImuSource& source, std::int64_t host_epoch_ns, Topic topic)
      : name_(source.name),
        clock_(source.clock, host_epoch_ns, kSbgCounterWrapNs),
        reader_(source.log),
        topic_(topic) {
    if (source.format == CanImuFormat::kSbg) {
      decoder_ = std::make_unique<imu::SbgCanDecoder>();
    } else {
      decoder_ = std::make_unique<imu::BoschMm7Decoder>();
    }
  }

 private:
  bool refill() override {
    if (!reader_.next(frame_)) return false;
    if (frame_.rtr || frame_.error) return true;
    decoder_->on_frame(imu::to_can_record(frame_), [this](const ImuSample& sample) {
      // A device clock maps back exactly (SBG); without one (MM7) the stamp is the receive time
      // of the sample's first frame, as a ROS driver stamps it.
      const std::int64_t stamp = decoder_->has_sensor_clock()
                                     ? clock_.host_ns(sample.stamp.sensor.ns, sample.stamp.host.ns)
                                     : sample.stamp.host.ns;
      enqueue(frame_.time_ns, topic_.connection, to_imu_msg(sample, stamp, name_, seq_));
      ++seq_;
      ++*topic_.count;
    });
    return true;
  }

  std::string name_;
  SensorClockInverse clock_;
  io::CandumpReader reader_;
  std::unique_ptr<imu::CanImuDecoder> decoder_;
  io::CanFrame frame_;
  Topic topic_;
  std::uint32_t seq_ = 0;
};

class CameraSource final : public QueuedSource {
 public:
  CameraSource(std::string name, std::vector<io::EurocImageRecord> records, Topic topic,
               std::uint64_t& missing)
      : name_(std::move(name)), records_(std::move(records)), topic_(topic), missing_(missing) {}

 private:
  bool refill() override {
    if (next_ >= records_.size()) return false;
    const io::EurocImageRecord& record = records_[next_++];
    if (!std::filesystem::exists(record.path)) {
      ++missing_;
      return true;
    }
    const auto image = load_image_message(record, name_, seq_);
    enqueue(record.timestamp.ns, topic_.connection, image);
    ++seq_;
    ++*topic_.count;
    return true;
  }

  std::string name_;
  std::vector<io::EurocImageRecord> records_;
  std::size_t next_ = 0;
  Topic topic_;
  std::uint64_t& missing_;
  std::uint32_t seq_ = 0;
};

// Topic names: the conventional one for the first sensor of a kind, /<name>/<leaf> after that.
class TopicNames {
 public:
  std::string take(const std::string& conventional, const std::string& name,
                   const std::string& leaf) {
    std::string topic = conventional;
    if (used_.contains(topic)) topic = "/" + name + "/" + leaf;
    if (!used_.insert(topic).second) throw Error("two bag topics named " + topic);
    return topic;
  }

 private:
  std::set<std::string> used_;
};

}  // namespace

ros::sensor_msgs::Image load_image_message(const io::EurocImageRecord& record,
                                           const std::string& frame_id, std::uint32_t seq) {
  const cv::Mat mat = io::load_euroc_image(record, io::ImageDecodeMode::kMono8);
  ros::sensor_msgs::Image image;
  image.header.seq = seq;
  image.header.stamp = ros_time(record.timestamp.ns);
  image.header.frame_id = frame_id;
  image.height = static_cast<std::uint32_t>(mat.rows);
  image.width = static_cast<std::uint32_t>(mat.cols);
  image.encoding = "mono8";
  image.step = image.width;
  image.data.resize(static_cast<std::size_t>(image.height) * image.step);
  for (int r = 0; r < mat.rows; ++r) {
    std::memcpy(image.data.data() + static_cast<std::size_t>(r) * image.step, mat.ptr(r),
                image.step);
  }
  return image;
}

std::unique_ptr<drivers::LidarDecoder> make_capture_decoder(
    const std::string& model, const std::optional<std::filesystem::path>& decoder_file) {
  const auto match = drivers::find_model(model);
  if (!match) throw Error("no LiDAR family has the model '" + model + "'");
  drivers::LidarDecoderConfig config;
  config.model = model;
  switch (match->family->file) {
    case drivers::DecoderFile::kMetadata:
      config.metadata = decoder_file;
      break;
    case drivers::DecoderFile::kCalibrationOptional:
    case drivers::DecoderFile::kCalibrationRequired:
      config.calibration = decoder_file;
      break;
    case drivers::DecoderFile::kNone:
      break;
  }
  return match->family->make_decoder(config);
}

double SensorClockInverse::scenario_time(std::int64_t sensor_ns, std::int64_t rx_ns) const {
  const double rate = 1.0 + faults_.skew_ppm * 1e-6;
  const double rx = static_cast<double>(rx_ns - host_epoch_ns_) * 1e-9;
  // The clock reads base + (t - start) * rate, valid for t in [from, to): before a reset (also
  // before t = 0, e.g. a scan window opening before the first point) and from the reset on.
  struct Segment {
    double base;
    double start;
    double from;
    double to;
  };
  constexpr double kForever = std::numeric_limits<double>::max();
  const bool reset = faults_.reset_at_s >= 0.0;
  const Segment segments[2] = {
      {faults_.offset_s, 0.0, -kForever, reset ? faults_.reset_at_s : kForever},
      {0.0, faults_.reset_at_s, faults_.reset_at_s, kForever}};
  std::optional<double> best;
  double best_lateness = 0.0;
  for (int k = 0; k < (reset ? 2 : 1); ++k) {
    const Segment& seg = segments[k];
    double reading = static_cast<double>(sensor_ns) * 1e-9;
    if (wrap_ns_ > 0) {
      // The wrap count that puts the reading where the clock stood at the receive time.
      const std::int64_t within = ((sensor_ns % wrap_ns_) + wrap_ns_) % wrap_ns_;
      const double wrap = static_cast<double>(wrap_ns_) * 1e-9;
      const double expected = seg.base + (rx - seg.start) * rate;
      const double periods = std::round((expected - static_cast<double>(within) * 1e-9) / wrap);
      reading = (static_cast<double>(within) + periods * static_cast<double>(wrap_ns_)) * 1e-9;
    }
    const double t = seg.start + (reading - seg.base) / rate;
    if (t < seg.from || t >= seg.to) continue;
    // An event precedes its receipt: the latest time not after the receive time wins.
    const double lateness = t <= rx ? rx - t : kForever / 2 + (t - rx);
    if (!best || lateness < best_lateness) {
      best = t;
      best_lateness = lateness;
    }
  }
  // Without a reset the single segment always gives a time; with one, a reading that fits
  // neither segment (a glitch) is mapped as if there had been no reset.
  if (!best) return (static_cast<double>(sensor_ns) * 1e-9 - faults_.offset_s) / rate;
  return *best;
}

std::int64_t lidar_stamp_wrap_ns(const std::string& model) {
  // Velodyne packets carry microseconds past the hour; the others a full sensor time.
  const auto match = drivers::find_model(model);
  return match ? match->family->sensor_time_wrap_ns : 0;
}

std::int64_t SensorClockInverse::host_ns(std::int64_t sensor_ns, std::int64_t rx_ns) const {
  return host_epoch_ns_ + std::llround(scenario_time(sensor_ns, rx_ns) * 1e9);
}

ros::livox_ros_driver::CustomMsg to_custom_msg(const LidarScan& scan, std::int64_t start_host_ns,
                                               const std::string& frame_id, std::uint32_t seq) {
  const std::int64_t shift = stamp_shift_ns(scan);
  const std::int64_t stamp = start_host_ns + shift;
  ros::livox_ros_driver::CustomMsg msg;
  msg.header.seq = seq;
  msg.header.stamp = ros_time(stamp);
  msg.header.frame_id = frame_id;
  msg.timebase = static_cast<std::uint64_t>(stamp);
  msg.points.reserve(valid_count(scan));
  for (std::size_t i = 0; i < scan.size(); ++i) {
    if (scan.valid[i] == 0) continue;
    ros::livox_ros_driver::CustomPoint p;
    p.offset_time = static_cast<std::uint32_t>(scan.t_offset_ns[i] - shift);
    p.x = scan.x[i];
    p.y = scan.y[i];
    p.z = scan.z[i];
    p.reflectivity =
        static_cast<std::uint8_t>(std::clamp(std::lround(scan.intensity[i]), 0L, 255L));
    // Tag 0: a normal return (no noise flags); FAST-LIO keeps tags whose bits 4-5 are 00 or 01.
    p.tag = 0;
    p.line = static_cast<std::uint8_t>(scan.ring[i]);
    msg.points.push_back(p);
  }
  msg.point_num = static_cast<std::uint32_t>(msg.points.size());
  return msg;
}

ros::sensor_msgs::PointCloud2 to_point_cloud2(const LidarScan& scan, CloudLayout layout,
                                              std::int64_t start_host_ns,
                                              const std::string& frame_id, std::uint32_t seq) {
  using Field = ros::sensor_msgs::PointField;
  const std::int64_t shift = stamp_shift_ns(scan);
  ros::sensor_msgs::PointCloud2 cloud;
  cloud.header.seq = seq;
  cloud.header.stamp = ros_time(start_host_ns + shift);
  cloud.header.frame_id = frame_id;
  const bool velodyne = layout == CloudLayout::kVelodyne;
  cloud.fields = {{"x", 0, Field::kFloat32, 1},
                  {"y", 4, Field::kFloat32, 1},
                  {"z", 8, Field::kFloat32, 1},
                  {"intensity", 12, Field::kFloat32, 1},
                  {"t", 16, Field::kUint32, 1},
                  // ouster_ros declares ring uint8, velodyne_pointcloud uint16: PCL matches types.
                  {"ring", 20, velodyne ? Field::kUint16 : Field::kUint8, 1}};
  if (velodyne) cloud.fields.push_back({"time", 24, Field::kFloat32, 1});
  cloud.point_step = velodyne ? 28 : 24;
  const std::size_t n = valid_count(scan);
  cloud.height = 1;
  cloud.width = static_cast<std::uint32_t>(n);
  cloud.row_step = cloud.point_step * cloud.width;
  cloud.is_bigendian = false;
  cloud.is_dense = true;
  cloud.data.assign(static_cast<std::size_t>(cloud.row_step), 0);
  std::size_t at = 0;
  for (std::size_t i = 0; i < scan.size(); ++i) {
    if (scan.valid[i] == 0) continue;
    const std::int64_t offset = scan.t_offset_ns[i] - shift;
    put(cloud.data, at + 0, scan.x[i]);
    put(cloud.data, at + 4, scan.y[i]);
    put(cloud.data, at + 8, scan.z[i]);
    put(cloud.data, at + 12, scan.intensity[i]);
    put(cloud.data, at + 16, static_cast<std::uint32_t>(offset));
    if (velodyne) {
      put(cloud.data, at + 20, scan.ring[i]);
      put(cloud.data, at + 24, static_cast<float>(static_cast<double>(offset) * 1e-9));
    } else {
      put(cloud.data, at + 20, static_cast<std::uint8_t>(scan.ring[i]));
    }
    at += cloud.point_step;
  }
  return cloud;
}

ros::sensor_msgs::Imu to_imu_msg(const ImuSample& sample, std::int64_t stamp_ns,
                                 const std::string& frame_id, std::uint32_t seq) {
  ros::sensor_msgs::Imu msg;
  msg.header.seq = seq;
  msg.header.stamp = ros_time(stamp_ns);
  msg.header.frame_id = frame_id;
  msg.orientation = {0.0, 0.0, 0.0, 1.0};
  msg.orientation_covariance[0] = -1.0;
  msg.angular_velocity = {sample.gyro_rad_s.x(), sample.gyro_rad_s.y(), sample.gyro_rad_s.z()};
  msg.linear_acceleration = {sample.accel_m_s2.x(), sample.accel_m_s2.y(), sample.accel_m_s2.z()};
  return msg;
}

SequenceBagReport write_sequence_bag(const std::filesystem::path& bag_path,
                                     const SequenceBagSpec& spec) {
  SequenceBagReport report;
  // The report's topic entries are referenced by the sources: reserve so they never move.
  report.topics.reserve(2 * spec.lidars.size() + spec.cameras.size() + 1);
  ros::BagWriter bag(bag_path, {.compression = spec.compression});
  TopicNames names;
  const auto add = [&](const std::string& topic, auto message_tag) {
    using Msg = decltype(message_tag);
    const std::uint32_t connection = bag.add_connection<Msg>(topic);
    report.topics.push_back({topic, std::string(ros::MessageTraits<Msg>::type), 0});
    return Topic{connection, &report.topics.back().messages};
  };

  std::vector<std::unique_ptr<MessageSource>> sources;
  for (const auto& lidar : spec.lidars) {
    std::optional<Topic> imu;
    Topic points;
    if (is_livox(lidar.model)) {
      points =
          add(names.take("/livox/lidar", lidar.name, "lidar"), ros::livox_ros_driver::CustomMsg{});
      if (lidar.imu)
        imu = add(names.take("/livox/imu", lidar.name, "imu"), ros::sensor_msgs::Imu{});
    } else if (is_ouster(lidar.model)) {
      points = add(names.take("/os_cloud_node/points", lidar.name, "points"),
                   ros::sensor_msgs::PointCloud2{});
      if (lidar.imu) {
        imu = add(names.take("/os_cloud_node/imu", lidar.name, "imu"), ros::sensor_msgs::Imu{});
      }
    } else if (is_hesai(lidar.model)) {
      // The Hesai ROS drivers' topic; livod's PointCloud2 layout as for the Velodynes.
      points =
          add(names.take("/hesai/pandar", lidar.name, "points"), ros::sensor_msgs::PointCloud2{});
    } else {
      points = add(names.take("/velodyne_points", lidar.name, "points"),
                   ros::sensor_msgs::PointCloud2{});
      // The HDL-32E's IMU (its position packets), on the topic of FAST_LIO's velodyne.yaml.
      if (lidar.imu && simulated_lidar_has_imu(lidar.model)) {
        imu = add(names.take("/imu/data", lidar.name, "imu"), ros::sensor_msgs::Imu{});
      }
    }
    sources.push_back(std::make_unique<LidarSource>(lidar, spec.host_epoch_ns, points, imu));
  }
  if (spec.can_imu) {
    const Topic topic = add(names.take("/imu", spec.can_imu->name, "imu"), ros::sensor_msgs::Imu{});
    sources.push_back(std::make_unique<CanImuSource>(*spec.can_imu, spec.host_epoch_ns, topic));
  }
  for (const auto& camera : spec.cameras) {
    auto records = io::read_euroc_camera_csv(camera.folder / "data.csv");
    // A run without PNG files (--no-images) has no image topic rather than an empty one.
    if (std::none_of(records.begin(), records.end(),
                     [](const auto& r) { return std::filesystem::exists(r.path); })) {
      report.missing_images += records.size();
      continue;
    }
    const Topic topic =
        add(names.take("/left_camera/image", camera.name, "image"), ros::sensor_msgs::Image{});
    sources.push_back(std::make_unique<CameraSource>(camera.name, std::move(records), topic,
                                                     report.missing_images));
  }

  // k-way merge by record time; ties go to the earlier source, so the order is deterministic.
  for (;;) {
    MessageSource* next = nullptr;
    std::int64_t next_ns = 0;
    for (const auto& s : sources) {
      const auto t = s->peek();
      if (t && (next == nullptr || *t < next_ns)) {
        next = s.get();
        next_ns = *t;
      }
    }
    if (next == nullptr) break;
    next->write_next(bag);
  }
  bag.close();
  return report;
}

}  // namespace livod::sim
