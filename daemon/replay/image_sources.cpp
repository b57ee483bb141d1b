#include "daemon/replay/image_sources.hpp"

#include "daemon/replay/image_decoding.hpp"

#include <fmt/core.h>

#include <algorithm>
#include <cctype>
#include <fstream>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>
#include <optional>
#include <sstream>

#include "core/error.hpp"
#include "core/image.hpp"
#include "io/euroc.hpp"
#include "io/rosbag/bag_reader.hpp"

namespace livod::daemon::replay {
namespace {

namespace rb = io::rosbag;

// Frames that all fail from the start mean a wrong folder or topic, not a damaged frame.
constexpr std::uint64_t kGiveUpAfter = 10;

struct FolderFrame {
  std::int64_t time_ns = 0;
  std::filesystem::path path;
  std::optional<Nanoseconds> exposure;
};

bool is_image_file(const std::filesystem::path& p) {
  std::string ext = p.extension().string();
  std::transform(ext.begin(), ext.end(), ext.begin(),
                 [](unsigned char c) { return static_cast<char>(std::tolower(c)); });
  return ext == ".png" || ext == ".jpg" || ext == ".jpeg" || ext == ".pgm" || ext == ".ppm" ||
         ext == ".bmp" || ext == ".tif" || ext == ".tiff";
}

std::string read_text(const std::filesystem::path& file) {
  std::ifstream in(file, std::ios::binary);
  if (!in) throw Error("cannot read " + file.string());
  std::stringstream ss;
  ss << in.rdbuf();
  return ss.str();
}

std::vector<FolderFrame> read_timestamps_txt(const std::filesystem::path& folder) {
  const auto file = folder / "timestamps.txt";
  std::vector<FolderFrame> frames;
  for (const auto& [ns, name] : parse_timestamps_txt(read_text(file), file.string())) {
    frames.push_back({ns, folder / name, std::nullopt});
  }
  return frames;
}

std::vector<FolderFrame> read_times_txt(const std::filesystem::path& folder) {
  const auto file = folder / "times.txt";
  std::vector<std::filesystem::path> images;
  for (const auto& entry : std::filesystem::directory_iterator(folder)) {
    if (entry.is_regular_file() && is_image_file(entry.path())) images.push_back(entry.path());
  }
  std::sort(images.begin(), images.end());
  const auto times = parse_times_txt(read_text(file), file.string());
  if (times.size() != images.size()) {
    throw Error(fmt::format("{}: {} times for {} images in {}", file.string(), times.size(),
                            images.size(), folder.string()));
  }
  std::vector<FolderFrame> frames;
  for (std::size_t i = 0; i < times.size(); ++i)
    frames.push_back({times[i], images[i], std::nullopt});
  return frames;
}

std::vector<FolderFrame> read_folder(const std::filesystem::path& folder) {
  if (!std::filesystem::is_directory(folder)) throw Error(folder.string() + " is not a folder");
  std::vector<FolderFrame> frames;
  if (std::filesystem::exists(folder / "data.csv")) {
    for (const auto& r : io::read_euroc_camera_csv(folder / "data.csv")) {
      frames.push_back({r.timestamp.ns, r.path, r.exposure});
    }
    return frames;  // the reader checked that the times increase
  }
  if (std::filesystem::exists(folder / "timestamps.txt")) {
    frames = read_timestamps_txt(folder);
  } else if (std::filesystem::exists(folder / "times.txt")) {
    frames = read_times_txt(folder);
  } else {
    throw Error(folder.string() +
                ": neither an EuRoC camera folder (data.csv) nor an image folder with "
                "timestamps.txt or times.txt");
  }
  for (std::size_t i = 1; i < frames.size(); ++i) {
    if (frames[i].time_ns <= frames[i - 1].time_ns) {
      throw Error(folder.string() + ": frame times must increase (" + frames[i].path.string() +
                  ")");
    }
  }
  return frames;
}

// Counts frames that cannot be used and gives up when the first ones all fail.
class FrameErrors {
 public:
  explicit FrameErrors(std::string where) : where_(std::move(where)) {}
  void ok() { ++ok_; }
  void failed(const std::exception& e) {
    if (count_++ == 0) first_ = e.what();
    if (ok_ == 0 && count_ >= kGiveUpAfter) {
      throw Error(where_ + ": the first " + std::to_string(count_) +
                  " frames cannot be read: " + first_);
    }
  }
  [[nodiscard]] std::uint64_t count() const { return count_; }
  [[nodiscard]] std::uint64_t good() const { return ok_; }

 private:
  std::string where_;
  std::string first_;
  std::uint64_t count_ = 0;
  std::uint64_t ok_ = 0;
};

class ImageFolderSource final : public ReplaySource {
 public:
  ImageFolderSource(const std::filesystem::path& folder, std::string sensor)
      : frames_(read_folder(folder)),
        errors_("sensor '" + sensor + "' (" + folder.string() + ")") {}

  std::optional<std::int64_t> peek_time() override {
    if (next_ >= frames_.size()) return std::nullopt;
    return frames_[next_].time_ns;
  }

  void deliver(const drivers::DecoderSinks& sinks) override {
    const FolderFrame& f = frames_[next_++];
    ImageFrame frame;
    try {
      const cv::Mat raw = cv::imread(f.path.string(), cv::IMREAD_UNCHANGED);
      if (raw.empty()) throw Error("cannot read or decode " + f.path.string());
      frame.image = to_mono_or_bgr(raw);
    } catch (const std::exception& e) {
      errors_.failed(e);
      return;
    }
    errors_.ok();
    frame.stamp.sensor = SensorTime(f.time_ns);
    frame.stamp.host = HostTime(f.time_ns);
    frame.exposure = f.exposure.value_or(Nanoseconds(0));
    frame.sequence = static_cast<std::uint32_t>(next_ - 1);
    frame.stamp_marks = ImageStampMarks::mid_exposure;
    if (sinks.on_image) sinks.on_image(frame);
  }

  void finish(const drivers::DecoderSinks& /*sinks*/) override {}

  [[nodiscard]] std::string summary() const override {
    return fmt::format("frames {} of {}, unreadable {}", errors_.good(), frames_.size(),
                       errors_.count());
  }
  [[nodiscard]] std::optional<double> fraction_done() const override {
    return frames_.empty() ? std::nullopt
                           : std::optional<double>(static_cast<double>(next_) /
                                                   static_cast<double>(frames_.size()));
  }

 private:
  std::vector<FolderFrame> frames_;
  std::size_t next_ = 0;
  FrameErrors errors_;
};

class BagImageSource final : public ReplaySource {
 public:
  BagImageSource(const std::filesystem::path& file, const std::string& topic, std::string sensor)
      : bag_(file), errors_("sensor '" + sensor + "' (" + file.string() + " " + topic + ")") {
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
    compressed_ = type_ == rb::MessageTraits<rb::sensor_msgs::CompressedImage>::type;
    if (!compressed_ && type_ != rb::MessageTraits<rb::sensor_msgs::Image>::type) {
      throw Error("topic " + topic + " is " + type_ +
                  ", not sensor_msgs/Image or sensor_msgs/CompressedImage");
    }
    start_ns_ = bag_.start_time_ns().value_or(0);
    end_ns_ = bag_.end_time_ns().value_or(0);
    rb::BagQuery query;
    query.topics = {topic};
    cursor_.emplace(bag_.read(query));
  }

  std::optional<std::int64_t> peek_time() override {
    if (!pending_ && !ended_) {
      pending_ = cursor_->next();
      ended_ = !pending_;
    }
    if (!pending_) return std::nullopt;
    return pending_->time_ns;
  }

  void deliver(const drivers::DecoderSinks& sinks) override {
    peek_time();
    if (!pending_) return;
    const rb::BagMessage m = *pending_;
    pending_.reset();
    last_ns_ = m.time_ns;
    ImageFrame frame;
    try {
      if (compressed_) {
        m.decode_into(compressed_msg_);
        frame.image = decode_compressed_image(compressed_msg_);
        frame.stamp.sensor = SensorTime(compressed_msg_.header.stamp.to_ns());
      } else {
        m.decode_into(image_msg_);
        frame.image = decode_image_message(image_msg_);
        frame.stamp.sensor = SensorTime(image_msg_.header.stamp.to_ns());
      }
    } catch (const std::exception& e) {
      errors_.failed(e);
      return;
    }
    errors_.ok();
    frame.stamp.host = HostTime(m.time_ns);
    frame.sequence = static_cast<std::uint32_t>(errors_.good() - 1);
    frame.stamp_marks = ImageStampMarks::mid_exposure;
    if (sinks.on_image) sinks.on_image(frame);
  }

  void finish(const drivers::DecoderSinks& /*sinks*/) override {}

  [[nodiscard]] std::string summary() const override {
    return fmt::format("{} frames {}, undecodable {}", compressed_ ? "compressed" : "raw",
                       errors_.good(), errors_.count());
  }
  [[nodiscard]] std::optional<double> fraction_done() const override {
    if (end_ns_ <= start_ns_) return std::nullopt;
    return static_cast<double>(last_ns_ - start_ns_) / static_cast<double>(end_ns_ - start_ns_);
  }

 private:
  rb::BagReader bag_;
  std::string type_;
  bool compressed_ = false;
  std::optional<rb::MessageCursor> cursor_;
  std::optional<rb::BagMessage> pending_;
  bool ended_ = false;
  std::int64_t start_ns_ = 0;
  std::int64_t end_ns_ = 0;
  std::int64_t last_ns_ = 0;
  rb::sensor_msgs::Image image_msg_;
  rb::sensor_msgs::CompressedImage compressed_msg_;
  FrameErrors errors_;
};

}  // namespace

std::unique_ptr<ReplaySource> make_image_folder_source(const std::filesystem::path& folder,
                                                       const SensorConfig& sensor) {
  return std::make_unique<ImageFolderSource>(folder, sensor.name);
}

std::unique_ptr<ReplaySource> make_bag_image_source(const std::filesystem::path& file,
                                                    const std::string& topic,
                                                    const SensorConfig& sensor) {
  return std::make_unique<BagImageSource>(file, topic, sensor.name);
}

}  // namespace livod::daemon::replay
