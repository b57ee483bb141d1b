#include "daemon/record/recorder.hpp"

#include <spdlog/spdlog.h>

#include <algorithm>
#include <cstring>
#include <limits>
#include <optional>
#include <utility>

#include "core/error.hpp"
#include "core/realtime_offset.hpp"
#include "io/block_file.hpp"
#include "io/pcap_records.hpp"

namespace livod::daemon::record {
namespace {

constexpr std::size_t kMinTapPackets = 256;
constexpr std::size_t kMaxTapPackets = 16384;
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

struct Recorder::File {
  struct Stream {
    PacketStreamSpec spec;
    std::unique_ptr<drivers::capture::PacketRing> tap;
    std::uint64_t overruns_seen = 0;
  };

  File(const std::filesystem::path& path, std::size_t block_bytes) : out(path) {
    const auto header = io::pcap_file_header(/*nanosecond_resolution=*/true);
    if (const int err = out.append(header); err != 0) {
      throw Error("cannot write " + path.string() + ": " + std::strerror(err));
    }
    block.reserve(block_bytes + 70'000);  // a whole block plus the largest datagram's records
    stats.file = path;
    stats.file_bytes = out.size();
  }

  io::BlockFile out;
  io::UdpPcapEncoder encoder;
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

drivers::capture::PacketRing& Recorder::add_packet_stream(const PacketStreamSpec& spec) {
  if (started_) throw Error("Recorder: streams must be added before start()");
  auto it = std::find_if(files_.begin(), files_.end(),
                         [&](const auto& f) { return f->stats.sensor == spec.sensor; });
  if (it == files_.end()) {
    files_.push_back(
        std::make_unique<File>(options_.dir / (spec.sensor + ".pcap"), options_.block_bytes));
    files_.back()->stats.sensor = spec.sensor;
    it = files_.end() - 1;
  }
  File& f = **it;
  const std::size_t slot = std::max<std::size_t>(spec.slot_bytes, 1);
  const std::size_t capacity =
      std::clamp(options_.stream_buffer_bytes / slot, kMinTapPackets, kMaxTapPackets);
  f.streams.push_back({spec, std::make_unique<drivers::capture::PacketRing>(capacity, slot), 0});
  f.stats.streams.push_back(spec.stream);
  return *f.streams.back().tap;
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
              "record: {}: {} ({} packets lost; the file keeps its {} written; retrying every "
              "{:.1f} s, losing what arrives meanwhile)",
              f.stats.file.string(), reason, f.block_packets, mb(f.out.size()),
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
      for (auto& s : f.streams) {
        const auto* p = s.tap->front();
        if (p != nullptr && p->rx.ns <= horizon &&
            (next == nullptr || p->rx < next->tap->front()->rx)) {
          next = &s;
        }
      }
      if (next == nullptr) break;
      did = true;
      const drivers::capture::RawPacket& p = *next->tap->front();
      const std::int64_t t = p.rx.ns + realtime_offset_ns_;
      f.newest_ns = std::max(f.newest_ns, t);
      if (p.truncated) {
        ++f.stats.lost_truncated;
        note_loss(f.stats, kTruncated, t, t, 1, p.payload.size());
      } else if (f.failing_until && now < *f.failing_until && !final) {
        ++f.stats.lost_write_failed;
        note_loss(f.stats, f.failing_reason, t, t, 1, p.payload.size());
      } else {
        if (!f.block.empty() &&
            f.block.size() + f.encoder.record_bytes(p.payload.size()) > options_.block_bytes) {
          write_block();
        }
        if (f.block.empty()) {
          f.block_first_ns = t;
          f.block_started = now;
        }
        f.encoder.append(f.block, t, p.src_ip, p.src_port, next->spec.dst_ip, p.dst_port,
                         p.payload);
        f.block_last_ns = t;
        ++f.block_packets;
        f.block_payload += p.payload.size();
      }
      next->tap->pop();
    }
    // Overflows of the taps: the capture threads dropped these (never seen: dated by the newest
    // packet drained).
    for (auto& s : f.streams) {
      const std::uint64_t overruns = s.tap->overruns();
      if (overruns != s.overruns_seen) {
        const std::uint64_t lost = overruns - s.overruns_seen;
        if (f.stats.lost_buffer_full == 0) {
          spdlog::warn("record: {}: {} '{}' packets dropped: {}", f.stats.file.filename().string(),
                       lost, s.spec.stream, kBufferFull);
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
  return did;
}

void Recorder::publish_stats() {
  std::vector<FileStats> snapshot;
  snapshot.reserve(files_.size());
  for (const auto& f : files_) snapshot.push_back(f->stats);
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
  publish_stats();
  for (const auto& s : stats()) {
    if (s.lost() > 0) problems.push_back("record: " + format_file_stats(s));
  }
  return problems;
}

std::string format_file_stats(const FileStats& s) {
  std::string line = s.file.filename().string() + ": " + std::to_string(s.packets) + " packets, " +
                     mb(s.file_bytes);
  if (s.first_ns != 0) {
    char span[32];
    std::snprintf(span, sizeof(span), ", %.1f s",
                  static_cast<double>(s.last_ns - s.first_ns) * 1e-9);
    line += span;
  }
  line += "; lost " + std::to_string(s.lost()) + " packets";
  if (s.lost() > 0) {
    line += " (buffer full " + std::to_string(s.lost_buffer_full) + ", write failed " +
            std::to_string(s.lost_write_failed) + ", truncated " +
            std::to_string(s.lost_truncated) + ")";
    if (!s.last_error.empty()) line += "; last error: " + s.last_error;
  }
  return line;
}

}  // namespace livod::daemon::record
