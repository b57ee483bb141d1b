#include "daemon/record/recorder.hpp"

#include <spdlog/spdlog.h>

#include <algorithm>
#include <cstring>
#include <limits>
#include <optional>
#include <stdexcept>
#include <utility>

#include "core/error.hpp"
#include "core/realtime_offset.hpp"
#include "drivers/imu/candump_frames.hpp"
#include "io/block_file.hpp"
#include "io/candump.hpp"
#include "io/euroc_writer.hpp"
#include "io/output_file.hpp"
#include "io/pcap_records.hpp"
#include "io/serial_capture.hpp"

namespace livod::daemon::record {
namespace {

constexpr std::size_t kMinTapPackets = 256;
constexpr std::size_t kMaxTapPackets = 16384;
constexpr std::size_t kMinTapFrames = 4;  // camera taps
constexpr std::size_t kMaxTapFrames = 64;
// Frames a camera writes per turn of the recorder thread (PNG encoding is slow: the LiDARs' and
// IMUs' taps are served between them).
constexpr int kFramesPerTurn = 2;
// A loss span is merged with the previous one of the same reason when they are this close.
constexpr std::int64_t kMergeLossNs = 1'000'000'000;
constexpr std::size_t kMaxLossSpans = 1000;  // beyond: merged into the last one
// Idle sleep of the recorder thread (it polls its taps; a capture thread never waits for it).
constexpr Nanoseconds kIdleSleep{5'000'000};

const std::string kBufferFull = "buffer full (the recorder or the disk fell behind)";
const std::string kTruncated = "datagram longer than its capture slot (truncated, not written)";

void note_loss(FileStats& s, const std::string& reason, std::int64_t first_ns, std::int64_t last_ns,
               std::uint64_t packets, std::uint64_t bytes) {
  if (packets == 0) return;
  if (!s.losses.empty()) {
    LossSpan& last = s.losses.back();
    if ((last.reason == reason && first_ns - last.last_ns <= kMergeLossNs) ||
        s.losses.size() >= kMaxLossSpans) {
      last.last_ns = std::max(last.last_ns, last_ns);
      last.packets += packets;
      last.bytes += bytes;
      return;
    }
  }
  s.losses.push_back({reason, first_ns, last_ns, packets, bytes});
}

std::string mb(std::uint64_t bytes) {
  char text[32];
  std::snprintf(text, sizeof(text), "%.1f MB", static_cast<double>(bytes) / 1e6);
  return text;
}

}  // namespace

using Format = RecordedFormat;

struct Recorder::File {
  // One tap: packets (a LiDAR port, a serial IMU's reads) or CAN frames.
  struct Stream {
    std::string name;
    std::uint32_t dst_ip = 0;  // pcap: the frames' destination
    std::unique_ptr<drivers::capture::PacketRing> packets;
    std::unique_ptr<SpscRing<imu::CanRecord>> frames;
    std::uint64_t overruns_seen = 0;

    // The receive time (CLOCK_MONOTONIC ns) of the oldest queued record.
    [[nodiscard]] std::optional<std::int64_t> front_ns() {
      if (packets) {
        const auto* p = packets->front();
        return p != nullptr ? std::optional(p->rx.ns) : std::nullopt;
      }
      const auto* f = frames->front();
      return f != nullptr ? std::optional(f->rx_time_ns) : std::nullopt;
    }
    void pop() {
      if (packets) {
        packets->pop();
      } else {
        frames->pop();
      }
    }
    [[nodiscard]] std::uint64_t overruns() const {
      return packets ? packets->overruns() : frames->overruns();
    }
  };

  File(const std::filesystem::path& path, Format file_format, std::size_t block_bytes)
      : out(path), format(file_format) {
    std::vector<std::byte> header;
    if (format == Format::pcap) {
      const auto pcap = io::pcap_file_header(/*nanosecond_resolution=*/true);
      header.assign(pcap.begin(), pcap.end());
    }
    if (format == Format::serial) header = io::serial_capture_header();
    if (const int err = header.empty() ? 0 : out.append(header); err != 0) {
      throw Error("cannot write " + path.string() + ": " + std::strerror(err));
    }
    // A whole block plus the largest record (a fragmented 64 KiB datagram, a serial read).
    block.reserve(block_bytes + 70'000);
    stats.file = path;
    stats.file_bytes = out.size();
    stats.unit = format == Format::pcap      ? "packets"
                 : format == Format::candump ? "frames"
                                             : "reads";
  }

  io::BlockFile out;
  Format format;
  io::UdpPcapEncoder encoder;
  std::string can_interface;  // candump: the bus name of every line
  std::string line;           // candump: the line being encoded
  std::vector<Stream> streams;
  std::vector<std::byte> block;
  // The records in `block`: written together or lost together.
  std::uint64_t block_packets = 0;
  std::uint64_t block_payload = 0;
  std::int64_t block_first_ns = 0;
  std::int64_t block_last_ns = 0;
  std::optional<HostTime> block_started;
  std::optional<HostTime> failing_until;  // after a failed write: lose packets until then
  std::string failing_reason;
  HostTime last_sync{0};
  std::int64_t newest_ns = 0;  // newest record time drained (dates buffer overflows)
  FileStats stats;
};

struct Recorder::CameraFolder {
  CameraFolder(const std::filesystem::path& folder, const CameraStreamSpec& spec,
               std::size_t capacity)
      : tap(capacity, std::max<std::size_t>(spec.frame_bytes, 1)),
        clock(spec.clock),
        writer(folder) {
    stats.sensor = spec.sensor;
    stats.file = folder;
    stats.streams.push_back("frames");
    stats.unit = "frames";
  }

  camera::FrameRing tap;
  camera::CameraClock clock;
  io::EurocCameraWriter writer;
  std::uint64_t overruns_seen = 0;
  std::optional<HostTime> unflushed_since;  // rows written to data.csv since its last flush
  HostTime last_sync{0};
  std::int64_t newest_ns = 0;
  FileStats stats;
};

Recorder::Recorder(RecorderOptions options) : options_(std::move(options)) {
  std::error_code ec;
  std::filesystem::create_directories(options_.dir, ec);
  if (ec)
    throw Error("cannot create the recording folder " + options_.dir.string() + ": " +
                ec.message());
  realtime_offset_ns_ = RealtimeToMonotonic().offset_ns();
}

Recorder::~Recorder() {
  stop();
}

Recorder::File& Recorder::new_file(const std::string& sensor, const std::string& extension,
                                   RecordedFormat format) {
  files_.push_back(
      std::make_unique<File>(options_.dir / (sensor + extension), format, options_.block_bytes));
  files_.back()->stats.sensor = sensor;
  return *files_.back();
}

drivers::capture::PacketRing& Recorder::add_packet_stream(const PacketStreamSpec& spec) {
  if (started_) throw Error("Recorder: streams must be added before start()");
  auto it = std::find_if(files_.begin(), files_.end(), [&](const auto& f) {
    return f->stats.sensor == spec.sensor && f->format == Format::pcap;
  });
  File& f = it != files_.end() ? **it : new_file(spec.sensor, ".pcap", Format::pcap);
  const std::size_t slot = std::max<std::size_t>(spec.slot_bytes, 1);
  const std::size_t capacity =
      std::clamp(options_.stream_buffer_bytes / slot, kMinTapPackets, kMaxTapPackets);
  File::Stream stream;
  stream.name = spec.stream;
  stream.dst_ip = spec.dst_ip;
  stream.packets = std::make_unique<drivers::capture::PacketRing>(capacity, slot);
  f.streams.push_back(std::move(stream));
  f.stats.streams.push_back(spec.stream);
  return *f.streams.back().packets;
}

SpscRing<imu::CanRecord>& Recorder::add_can_stream(const CanStreamSpec& spec) {
  if (started_) throw Error("Recorder: streams must be added before start()");
  if (spec.interface.empty()) throw Error("Recorder: CAN IMU '" + spec.sensor + "' without bus");
  File& f = new_file(spec.sensor, ".log", Format::candump);
  f.can_interface = spec.interface;
  const std::size_t capacity = std::clamp(options_.stream_buffer_bytes / sizeof(imu::CanRecord),
                                          kMinTapPackets, kMaxTapPackets);
  File::Stream stream;
  stream.name = "can";
  stream.frames = std::make_unique<SpscRing<imu::CanRecord>>(capacity);
  // Touch every slot now (no capture thread runs yet), so that the capture thread never takes a
  // page fault on the tap in steady state, as PacketRing does for its arena.
  for (std::size_t i = 0; i < capacity; ++i) stream.frames->try_push(imu::CanRecord{});
  while (stream.frames->front() != nullptr) stream.frames->pop();
  f.streams.push_back(std::move(stream));
  f.stats.streams.push_back("can");
  return *f.streams.back().frames;
}

drivers::capture::PacketRing& Recorder::add_serial_stream(const SerialStreamSpec& spec) {
  if (started_) throw Error("Recorder: streams must be added before start()");
  File& f = new_file(spec.sensor, ".serial", Format::serial);
  const std::size_t slot = std::max<std::size_t>(spec.slot_bytes, 1);
  const std::size_t capacity =
      std::clamp(options_.stream_buffer_bytes / slot, kMinTapPackets, kMaxTapPackets);
  File::Stream stream;
  stream.name = "serial";
  stream.packets = std::make_unique<drivers::capture::PacketRing>(capacity, slot);
  f.streams.push_back(std::move(stream));
  f.stats.streams.push_back("serial");
  return *f.streams.back().packets;
}

camera::FrameRing& Recorder::add_camera_stream(const CameraStreamSpec& spec) {
  if (started_) throw Error("Recorder: streams must be added before start()");
  const std::size_t capacity =
      std::clamp(options_.stream_buffer_bytes / std::max<std::size_t>(spec.frame_bytes, 1),
                 kMinTapFrames, kMaxTapFrames);
  cameras_.push_back(std::make_unique<CameraFolder>(options_.dir / spec.sensor, spec, capacity));
  return cameras_.back()->tap;
}

void Recorder::expect_metadata(const std::string& sensor) {
  if (started_) throw Error("Recorder: metadata must be expected before start()");
  metadata_.push_back({sensor, "", 0});
}

void Recorder::save_metadata(const std::string& sensor, std::string json) {
  const std::lock_guard lock(metadata_mutex_);
  metadata_queue_.emplace_back(sensor, std::move(json));
}

bool Recorder::write_metadata() {
  std::vector<std::pair<std::string, std::string>> queued;
  {
    const std::lock_guard lock(metadata_mutex_);
    queued.swap(metadata_queue_);
  }
  for (auto& [sensor, json] : queued) {
    auto m = std::find_if(metadata_.begin(), metadata_.end(),
                          [&](const Metadata& x) { return x.sensor == sensor; });
    if (m == metadata_.end() || json == m->last_json) continue;  // unexpected, or unchanged
    const std::string name = m->written == 0
                                 ? sensor + ".json"
                                 : sensor + ".reinit-" + std::to_string(m->written) + ".json";
    std::string note;
    try {
      io::write_file(options_.dir / name, json);
      note = m->written == 0 ? name + ": the metadata fetched from the sensor"
                             : name + ": the metadata after the sensor re-initialised (" + sensor +
                                   ".json describes the packets before it)";
      if (m->written > 0) spdlog::warn("record: {}", note);
      m->last_json = std::move(json);
      ++m->written;
    } catch (const std::exception& e) {
      note = name + ": not written: " + e.what();
      spdlog::error("record: {}", note);
    }
    for (auto& f : files_) {
      if (f->stats.sensor == sensor) f->stats.notes.push_back(note);
    }
  }
  return !queued.empty();
}

void Recorder::start() {
  if (started_) return;
  started_ = true;
  publish_stats();
  thread_ = std::jthread([this](const std::stop_token& stop) { run(stop); });
}

void Recorder::run(const std::stop_token& stop) {
  pthread_setname_np(pthread_self(), "livod-rec");
  while (!stop.stop_requested()) {
    heartbeat_.beat();
    const bool did = turn(host_now(), /*final=*/false);
    publish_stats();
    if (!did) std::this_thread::sleep_for(kIdleSleep);
  }
}

bool Recorder::turn(HostTime now, bool final) {
  bool did = false;
  const std::int64_t horizon =
      final ? std::numeric_limits<std::int64_t>::max() : (now - options_.hold_back).ns;
  for (auto& fp : files_) {
    File& f = *fp;
    const auto write_block = [&] {
      if (f.block.empty()) return;
      const int err = f.out.append(f.block);
      if (err == 0) {
        f.stats.packets += f.block_packets;
        f.stats.payload_bytes += f.block_payload;
        if (f.stats.first_ns == 0) f.stats.first_ns = f.block_first_ns;
        f.stats.last_ns = f.block_last_ns;
        f.stats.file_bytes = f.out.size();
        if (f.failing_until) {
          spdlog::info("record: {}: writing again after '{}'", f.stats.file.filename().string(),
                       f.failing_reason);
          f.failing_until.reset();
        }
      } else {
        const std::string reason = std::string("write failed: ") + std::strerror(err);
        f.stats.lost_write_failed += f.block_packets;
        note_loss(f.stats, reason, f.block_first_ns, f.block_last_ns, f.block_packets,
                  f.block_payload);
        if (!f.failing_until) {
          spdlog::error(
              "record: {}: {} ({} {} lost; the file keeps its {} written; retrying every "
              "{:.1f} s, losing what arrives meanwhile)",
              f.stats.file.string(), reason, f.block_packets, f.stats.unit, mb(f.out.size()),
              to_seconds(options_.retry_period));
        }
        f.stats.last_error = std::strerror(err);
        f.failing_reason = reason;
        f.failing_until = now + options_.retry_period;
      }
      f.block.clear();
      f.block_packets = 0;
      f.block_payload = 0;
      f.block_started.reset();
    };

    // Merge the streams in receive-time order, up to the horizon.
    for (;;) {
      File::Stream* next = nullptr;
      std::int64_t next_ns = 0;
      for (auto& s : f.streams) {
        const auto rx = s.front_ns();
        if (rx && *rx <= horizon && (next == nullptr || *rx < next_ns)) {
          next = &s;
          next_ns = *rx;
        }
      }
      if (next == nullptr) break;
      did = true;
      const std::int64_t t = next_ns + realtime_offset_ns_;
      f.newest_ns = std::max(f.newest_ns, t);
      // The record's payload and encoded size.
      const drivers::capture::RawPacket* p = next->packets ? next->packets->front() : nullptr;
      const imu::CanRecord* frame = next->frames ? next->frames->front() : nullptr;
      const std::size_t payload = p != nullptr ? p->payload.size() : frame->len;
      std::size_t record_bytes = 0;
      std::string invalid;
      if (f.format == Format::pcap) {
        record_bytes = f.encoder.record_bytes(payload);
      } else if (f.format == Format::serial) {
        record_bytes = io::serial_record_bytes(payload);
      } else {
        try {
          io::CanFrame c = imu::to_candump_frame(*frame, f.can_interface);
          c.time_ns = t;
          f.line = io::format_candump_line(c);
          f.line += '\n';
          record_bytes = f.line.size();
        } catch (const std::invalid_argument& e) {
          invalid = std::string("not a candump frame: ") + e.what();
        }
      }
      if (p != nullptr && p->truncated) {
        ++f.stats.lost_truncated;
        note_loss(f.stats, kTruncated, t, t, 1, payload);
      } else if (!invalid.empty()) {
        ++f.stats.lost_invalid;
        note_loss(f.stats, invalid, t, t, 1, payload);
      } else if (f.failing_until && now < *f.failing_until && !final) {
        ++f.stats.lost_write_failed;
        note_loss(f.stats, f.failing_reason, t, t, 1, payload);
      } else {
        if (!f.block.empty() && f.block.size() + record_bytes > options_.block_bytes) {
          write_block();
        }
        if (f.block.empty()) {
          f.block_first_ns = t;
          f.block_started = now;
        }
        if (f.format == Format::pcap) {
          f.encoder.append(f.block, t, p->src_ip, p->src_port, next->dst_ip, p->dst_port,
                           p->payload);
        } else if (f.format == Format::serial) {
          io::append_serial_record(f.block, t, p->payload);
        } else {
          const auto* bytes = reinterpret_cast<const std::byte*>(f.line.data());
          f.block.insert(f.block.end(), bytes, bytes + f.line.size());
        }
        f.block_last_ns = t;
        ++f.block_packets;
        f.block_payload += payload;
      }
      next->pop();
    }
    // Overflows of the taps: the capture threads dropped these (never seen: dated by the newest
    // packet drained).
    for (auto& s : f.streams) {
      const std::uint64_t overruns = s.overruns();
      if (overruns != s.overruns_seen) {
        const std::uint64_t lost = overruns - s.overruns_seen;
        if (f.stats.lost_buffer_full == 0) {
          spdlog::warn("record: {}: {} '{}' {} dropped: {}", f.stats.file.filename().string(), lost,
                       s.name, f.stats.unit, kBufferFull);
        }
        f.stats.lost_buffer_full += lost;
        note_loss(f.stats, kBufferFull, f.newest_ns, f.newest_ns, lost, 0);
        s.overruns_seen = overruns;
      }
    }
    if (f.block_started && (final || now - *f.block_started >= options_.flush_period)) {
      write_block();
    }
    if (!final && now - f.last_sync >= options_.sync_period) {
      f.out.sync();
      f.last_sync = now;
    }
  }
  if (turn_cameras(now, final)) did = true;
  if (write_metadata()) did = true;
  return did;
}

bool Recorder::turn_cameras(HostTime now, bool final) {
  bool did = false;
  for (auto& cp : cameras_) {
    CameraFolder& c = *cp;
    for (int n = 0; final || n < kFramesPerTurn; ++n) {
      const camera::FrameRing::Entry* entry = c.tap.front();
      if (entry == nullptr) break;
      did = true;
      camera::CameraFrame frame;
      frame.info = entry->info;
      frame.image =
          cv::Mat(entry->info.height, entry->info.width, camera::cv_type(entry->info.format),
                  const_cast<std::byte*>(entry->pixels.data()), entry->info.stride);
      c.clock.map(frame);
      const std::int64_t t = frame.mid_exposure.ns + realtime_offset_ns_;
      const std::uint64_t bytes =
          static_cast<std::uint64_t>(entry->info.height) * entry->info.stride;
      c.newest_ns = std::max(c.newest_ns, t);
      try {
        std::optional<Nanoseconds> exposure;
        if (frame.info.exposure.count() > 0) exposure = frame.info.exposure;
        c.writer.write(SensorTime(t), frame.image, exposure);
        ++c.stats.packets;
        c.stats.payload_bytes += bytes;
        if (c.stats.first_ns == 0) c.stats.first_ns = t;
        c.stats.last_ns = t;
        c.stats.file_bytes = c.writer.bytes();
        if (!c.unflushed_since) c.unflushed_since = now;
      } catch (const std::invalid_argument& e) {
        // A frame time not after the previous one (a camera clock stepping back).
        ++c.stats.lost_invalid;
        note_loss(c.stats, std::string("not written: ") + e.what(), t, t, 1, bytes);
      } catch (const std::exception& e) {
        const std::string reason = std::string("write failed: ") + e.what();
        if (c.stats.lost_write_failed == 0) {
          spdlog::error("record: {}: {} (the frame is lost; the frames written stay)",
                        c.stats.file.string(), reason);
        }
        ++c.stats.lost_write_failed;
        c.stats.last_error = e.what();
        note_loss(c.stats, reason, t, t, 1, bytes);
      }
      frame.image = cv::Mat();
      c.tap.pop();
    }
    if (const std::uint64_t overruns = c.tap.overruns(); overruns != c.overruns_seen) {
      const std::uint64_t lost = overruns - c.overruns_seen;
      if (c.stats.lost_buffer_full == 0) {
        spdlog::warn("record: {}: {} frames dropped: {}", c.stats.file.filename().string(), lost,
                     kBufferFull);
      }
      c.stats.lost_buffer_full += lost;
      note_loss(c.stats, kBufferFull, c.newest_ns, c.newest_ns, lost, 0);
      c.overruns_seen = overruns;
    }
    if (c.unflushed_since && (final || now - *c.unflushed_since >= options_.flush_period)) {
      try {
        c.writer.flush();
      } catch (const std::exception& e) {
        c.stats.last_error = e.what();
        spdlog::error("record: {}", e.what());
      }
      c.unflushed_since.reset();
    }
  }
  return did;
}

void Recorder::publish_stats() {
  std::vector<FileStats> snapshot;
  snapshot.reserve(files_.size() + cameras_.size());
  for (const auto& f : files_) snapshot.push_back(f->stats);
  for (const auto& c : cameras_) snapshot.push_back(c->stats);
  const std::lock_guard lock(stats_mutex_);
  stats_ = std::move(snapshot);
}

std::vector<FileStats> Recorder::stats() const {
  const std::lock_guard lock(stats_mutex_);
  return stats_;
}

std::vector<std::string> Recorder::stop() {
  if (stopped_) return {};
  stopped_ = true;
  if (thread_.joinable()) {
    thread_.request_stop();
    thread_.join();
  }
  std::vector<std::string> problems;
  turn(host_now(), /*final=*/true);
  for (auto& f : files_) {
    if (const int err = f->out.close(); err != 0) {
      f->stats.last_error = std::strerror(err);
      problems.push_back("record: " + f->stats.file.string() + ": closing: " + std::strerror(err));
    }
  }
  for (const Metadata& m : metadata_) {
    if (m.written == 0) {
      const std::string note = m.sensor +
                               ".json: the sensor's metadata was never fetched (is it reachable "
                               "over HTTP?): the pcap replays only with it";
      problems.push_back("record: " + note);
      for (auto& f : files_) {
        if (f->stats.sensor == m.sensor) f->stats.notes.push_back(note);
      }
    }
  }
  publish_stats();
  for (const auto& s : stats()) {
    if (s.lost() > 0) problems.push_back("record: " + format_file_stats(s));
  }
  return problems;
}

std::string format_file_stats(const FileStats& s) {
  std::string line = s.file.filename().string() + ": " + std::to_string(s.packets) + " " + s.unit +
                     ", " + mb(s.file_bytes);
  if (s.first_ns != 0) {
    char span[32];
    std::snprintf(span, sizeof(span), ", %.1f s",
                  static_cast<double>(s.last_ns - s.first_ns) * 1e-9);
    line += span;
  }
  line += "; lost " + std::to_string(s.lost()) + " " + s.unit;
  if (s.lost() > 0) {
    line += " (buffer full " + std::to_string(s.lost_buffer_full) + ", write failed " +
            std::to_string(s.lost_write_failed) + ", truncated " + std::to_string(s.lost_truncated);
    if (s.lost_invalid > 0) line += ", not representable " + std::to_string(s.lost_invalid);
    line += ")";
    if (!s.last_error.empty()) line += "; last error: " + s.last_error;
  }
  return line;
}

}  // namespace livod::daemon::record
