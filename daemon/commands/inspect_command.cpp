// `livod inspect FILE...`: what a recorded file contains, without any sensor configuration.
//   pcap/pcapng    records, time span, UDP datagrams per destination port with their sources and
//                  a size histogram, IPv4 fragments reassembled, malformed/non-UDP counts
//   ROS1 bags      chunks and compression, whether the index is intact (a damaged bag is read by
//                  scanning its chunks), messages and time span, per topic: messages, mean rate,
//                  type and how `livod replay` reads it
//   candump logs   frames per CAN id with rate, lengths and interfaces, frame kinds
// The file type is recognised from its first bytes (kInspectors below: add new formats there).
// Every file is reported even if an earlier one fails; the exit code is 1 if any failed.

#include <fmt/core.h>
#include <CLI/CLI.hpp>

#include <algorithm>
#include <array>
#include <cstddef>
#include <cstdint>
#include <cstdio>
#include <cstring>
#include <ctime>
#include <exception>
#include <filesystem>
#include <fstream>
#include <map>
#include <memory>
#include <optional>
#include <set>
#include <span>
#include <stdexcept>
#include <string>
#include <string_view>
#include <tuple>
#include <vector>

#include "core/error.hpp"
#include "core/time.hpp"
#include "daemon/commands/command.hpp"
#include "io/candump.hpp"
#include "io/input_loss.hpp"
#include "io/pcap.hpp"
#include "io/rosbag/bag_reader.hpp"

namespace livod::daemon {
namespace {

namespace fs = std::filesystem;

constexpr std::size_t kHeadBytes = 64;
constexpr std::size_t kMaxSizesShown = 6;  // size histogram entries per port

std::vector<std::byte> read_head(const fs::path& path) {
  std::ifstream in(path, std::ios::binary);
  if (!in) throw std::runtime_error(path.string() + ": cannot open");
  std::vector<std::byte> head(kHeadBytes);
  in.read(reinterpret_cast<char*>(head.data()), static_cast<std::streamsize>(head.size()));
  head.resize(static_cast<std::size_t>(in.gcount()));  // an empty file gives an empty head
  return head;
}

// UTC calendar time of an epoch-ns stamp, with 6 or 9 fractional digits.
std::string utc(std::int64_t ns, int digits) {
  std::int64_t seconds = ns / kNsPerSecond;
  std::int64_t fraction = ns % kNsPerSecond;
  if (fraction < 0) {
    fraction += kNsPerSecond;
    --seconds;
  }
  const auto t = static_cast<std::time_t>(seconds);
  std::tm tm{};
  gmtime_r(&t, &tm);
  char date[32];
  std::strftime(date, sizeof date, "%Y-%m-%d %H:%M:%S", &tm);
  return digits == 9 ? fmt::format("{}.{:09d}", date, fraction)
                     : fmt::format("{}.{:06d}", date, fraction / 1000);
}

std::string time_span(std::int64_t first_ns, std::int64_t last_ns) {
  // Microsecond captures have whole microseconds; show nanoseconds only when they carry some.
  const int digits = (first_ns % 1000 != 0 || last_ns % 1000 != 0) ? 9 : 6;
  return fmt::format("{:.6f} s ({} .. {} UTC)",
                     static_cast<double>(last_ns - first_ns) / static_cast<double>(kNsPerSecond),
                     utc(first_ns, digits), utc(last_ns, digits).substr(11));
}

std::string dotted(std::uint32_t ip) {
  return fmt::format("{}.{}.{}.{}", ip >> 24, (ip >> 16) & 0xFF, (ip >> 8) & 0xFF, ip & 0xFF);
}

// "value x count" pairs, most frequent first, at most `limit` of them.
template <class Key>
std::string histogram(const std::map<Key, std::uint64_t>& counts, std::size_t limit,
                      auto&& format_key) {
  std::vector<std::pair<Key, std::uint64_t>> entries(counts.begin(), counts.end());
  std::stable_sort(entries.begin(), entries.end(),
                   [](const auto& a, const auto& b) { return a.second > b.second; });
  std::string out;
  for (std::size_t i = 0; i < entries.size() && i < limit; ++i) {
    if (!out.empty()) out += ", ";
    out += fmt::format("{} x{}", format_key(entries[i].first), entries[i].second);
  }
  if (entries.size() > limit) out += fmt::format(", +{} more", entries.size() - limit);
  return out;
}

// Every stretch the reader had to skip (damaged records, unparsable lines), then the totals.
void print_losses(const io::InputLossLog& losses) {
  for (const auto& loss : losses.entries()) fmt::print("  lost        {}\n", io::format_loss(loss));
  if (losses.not_listed() > 0) {
    fmt::print("  lost        {} more damaged stretches not listed\n", losses.not_listed());
  }
  if (!losses.empty()) {
    fmt::print("  damage      {} stretch(es), {} bytes skipped; the counts above cover the rest\n",
               losses.count(), losses.bytes());
  }
}

// ---------------------------------------------------------------------------------------------
// pcap / pcapng

bool is_capture(std::span<const std::byte> head) {
  if (head.size() < 4) return false;
  const std::uint32_t magic = (std::to_integer<std::uint32_t>(head[0]) << 24) |
                              (std::to_integer<std::uint32_t>(head[1]) << 16) |
                              (std::to_integer<std::uint32_t>(head[2]) << 8) |
                              std::to_integer<std::uint32_t>(head[3]);
  // Classic pcap (us and ns, either byte order) and the pcapng section header block.
  return magic == 0xA1B2C3D4 || magic == 0xD4C3B2A1 || magic == 0xA1B23C4D || magic == 0x4D3CB2A1 ||
         magic == 0x0A0D0D0A;
}

// One row of the table: datagrams to one port from one address. Several sensors often share a
// port (Ouster lidar + IMU, two sensors to one host), and source ports are often ephemeral, so
// rows are per (destination port, source address).
struct StreamSummary {
  std::uint64_t datagrams = 0;
  std::uint64_t bytes = 0;
  std::map<std::size_t, std::uint64_t> sizes;
  std::set<std::uint16_t> source_ports;
};

void inspect_capture(const fs::path& path) {
  io::PcapReader reader(path);
  std::map<std::pair<std::uint16_t, std::uint32_t>, StreamSummary> streams;
  while (auto datagram = reader.next()) {
    auto& stream = streams[{datagram->dst_port, datagram->src_ip}];
    ++stream.datagrams;
    stream.bytes += datagram->payload.size();
    ++stream.sizes[datagram->payload.size()];
    stream.source_ports.insert(datagram->src_port);
  }
  const io::PcapStats& s = reader.stats();
  const io::Ipv4ReassemblyStats& r = reader.reassembly_stats();

  fmt::print("  format      {}, link type {}\n", reader.is_pcapng() ? "pcapng" : "pcap",
             reader.link_type_name());
  fmt::print("  records     {}", s.records);
  if (s.records > 0) fmt::print(" over {}", time_span(s.min_record_time_ns, s.max_record_time_ns));
  fmt::print("\n  UDP         {} datagrams; non-UDP {}, malformed {}\n", s.udp_datagrams, s.non_udp,
             s.malformed);
  fmt::print("  IPv4        {} fragments -> {} datagrams reassembled, {} incomplete sets",
             s.fragments, s.reassembled, s.incomplete_fragments);
  if (r.duplicates + r.conflicts + r.invalid != 0) {
    fmt::print(" ({} duplicate, {} conflicting, {} invalid fragments)", r.duplicates, r.conflicts,
               r.invalid);
  }
  fmt::print("\n");
  if (s.ip_length_clamped != 0) {
    fmt::print(
        "  note        {} packets had an IPv4 total length beyond the frame (read to the "
        "frame end)\n",
        s.ip_length_clamped);
  }
  print_losses(reader.losses());
  if (streams.empty()) return;
  fmt::print("  {:>8}  {:<29}  {:>9}  {:>11}  {}\n", "dst port", "source", "datagrams", "bytes",
             "payload sizes (bytes xcount)");
  for (const auto& [key, stream] : streams) {
    const auto& [port, source_ip] = key;
    // One source port is shown; ephemeral ones are summarised as a count.
    const std::string source =
        stream.source_ports.size() == 1
            ? fmt::format("{}:{}", dotted(source_ip), *stream.source_ports.begin())
            : fmt::format("{} ({} ports)", dotted(source_ip), stream.source_ports.size());
    fmt::print("  {:>8}  {:<29}  {:>9}  {:>11}  {}\n", port, source, stream.datagrams, stream.bytes,
               histogram(stream.sizes, kMaxSizesShown, [](std::size_t n) { return n; }));
  }
}

// ---------------------------------------------------------------------------------------------
// candump logs

bool is_candump(std::span<const std::byte> head) {
  for (const std::byte b : head) {
    const char c = static_cast<char>(b);
    if (c == ' ' || c == '\t' || c == '\r' || c == '\n') continue;
    return c == '(';
  }
  return false;
}

// The id as the log writes it: 3 hex digits (11-bit), 8 (29-bit), or the error class.
using CanKey = std::tuple<int, std::uint32_t>;  // (0 standard, 1 extended, 2 error), id

std::string can_key_text(const CanKey& key) {
  const auto [kind, id] = key;
  if (kind == 2) return fmt::format("error {:08X}", id);
  return kind == 1 ? fmt::format("{:08X}", id) : fmt::format("{:03X}", id);
}

struct CanIdSummary {
  std::uint64_t frames = 0;
  std::uint64_t fd = 0;
  std::uint64_t rtr = 0;
  std::int64_t first_ns = 0;
  std::int64_t last_ns = 0;
  std::map<int, std::uint64_t> lengths;
  std::set<std::string> interfaces;
};

void inspect_candump(const fs::path& path) {
  io::CandumpReader reader(path, {.lenient = true});
  std::map<CanKey, CanIdSummary> ids;
  std::map<std::string, std::uint64_t> interfaces;
  std::uint64_t classic = 0, fd = 0, rtr = 0, errors = 0;
  std::int64_t first_ns = 0, last_ns = 0;
  io::CanFrame frame;
  while (reader.next(frame)) {
    const CanKey key{frame.error ? 2 : (frame.extended ? 1 : 0), frame.id};
    auto& s = ids[key];
    if (s.frames == 0) s.first_ns = frame.time_ns;
    s.last_ns = frame.time_ns;
    ++s.frames;
    ++s.lengths[frame.len];
    s.interfaces.insert(frame.interface);
    if (frame.fd) ++s.fd;
    if (frame.rtr) ++s.rtr;
    ++interfaces[frame.interface];
    if (reader.stats().frames == 1) first_ns = frame.time_ns;
    first_ns = std::min(first_ns, frame.time_ns);
    last_ns = std::max(last_ns, frame.time_ns);
    if (frame.error) {
      ++errors;
    } else if (frame.fd) {
      ++fd;
    } else {
      ++classic;
      if (frame.rtr) ++rtr;
    }
  }
  const auto& stats = reader.stats();
  fmt::print("  format      candump log (can-utils)\n");
  fmt::print("  frames      {}", stats.frames);
  if (stats.frames > 0) fmt::print(" over {}", time_span(first_ns, last_ns));
  fmt::print("\n  kinds       classic {} (of which RTR {}), CAN FD {}, error frames {}\n", classic,
             rtr, fd, errors);
  if (!interfaces.empty()) {
    fmt::print("  interfaces  {}\n",
               histogram(interfaces, interfaces.size(), [](const std::string& n) { return n; }));
  }
  fmt::print("  lines       {} read, {} malformed skipped\n", stats.lines, stats.skipped);
  print_losses(reader.losses());
  if (ids.empty()) return;
  fmt::print("  {:<14}  {:>8}  {:>9}  {:<12}  {}\n", "id", "frames", "rate Hz", "interfaces",
             "lengths (bytes xcount)");
  for (const auto& [key, s] : ids) {
    const double span_s = static_cast<double>(s.last_ns - s.first_ns) / 1e9;
    // Rate over the id's own span: frames - 1 intervals.
    const std::string rate = s.frames > 1 && span_s > 0
                                 ? fmt::format("{:.2f}", static_cast<double>(s.frames - 1) / span_s)
                                 : "-";
    std::string names;
    for (const auto& n : s.interfaces) names += (names.empty() ? "" : ",") + n;
    std::string flags;
    if (s.fd != 0) flags += fmt::format(" (FD {})", s.fd);
    if (s.rtr != 0) flags += fmt::format(" (RTR {})", s.rtr);
    fmt::print("  {:<14}  {:>8}  {:>9}  {:<12}  {}{}\n", can_key_text(key), s.frames, rate, names,
               histogram(s.lengths, kMaxSizesShown, [](int n) { return n; }), flags);
  }
}

// ---------------------------------------------------------------------------------------------
// ROS1 bags

bool is_bag(std::span<const std::byte> head) {
  constexpr std::string_view kMagic = "#ROSBAG V2.0\n";
  if (head.size() < kMagic.size()) return false;
  return std::memcmp(head.data(), kMagic.data(), kMagic.size()) == 0;
}

// How `livod replay` reads a topic of this type (daemon/replay/bag_sources.cpp): the driver a
// sensor needs to take it, or "-" when replay does not read the type.
std::string_view replayed_as(std::string_view type) {
  if (type == "sensor_msgs/Imu") return "dataset_imu";
  if (type == "sensor_msgs/PointCloud2" || type == "livox_ros_driver/CustomMsg" ||
      type == "livox_ros_driver2/CustomMsg") {
    return "dataset_lidar";
  }
  if (type == "ouster_ros/PacketMsg") return "ouster (packets)";
  return "-";
}

void inspect_bag(const fs::path& path) {
  // A bag whose recording was killed has no index: read what the chunks hold, and say so.
  std::optional<io::rosbag::BagReader> bag;
  std::string index_note = "intact";
  try {
    bag.emplace(path);
  } catch (const FormatError& e) {
    io::rosbag::BagReader::Options options;
    options.recover = true;
    bag.emplace(path, options);
    index_note = fmt::format("damaged, rebuilt by scanning the chunks ({})", e.what());
  }
  const auto compressions = bag->chunk_compressions();
  std::string chunks;
  for (const auto& [name, n] : compressions) {
    chunks += fmt::format("{}{} {}", chunks.empty() ? "" : ", ", name, n);
  }
  fmt::print("  format      ROS1 bag 2.0, {} chunks ({}), index {}\n", bag->chunk_count(),
             chunks.empty() ? "none" : chunks, index_note);
  const auto start = bag->start_time_ns();
  const auto end = bag->end_time_ns();
  fmt::print("  messages    {}", bag->message_count());
  if (start && end) fmt::print(" over {}", time_span(*start, *end));
  fmt::print("\n  connections {}\n", bag->connections().size());
  const auto topics = bag->topics();
  if (topics.empty()) return;
  const double span_s = start && end ? static_cast<double>(*end - *start) * 1e-9 : 0.0;
  std::size_t topic_width = 5;
  std::size_t type_width = 4;
  for (const auto& t : topics) {
    topic_width = std::max(topic_width, t.topic.size());
    type_width = std::max(type_width, t.type.size());
  }
  fmt::print("  {:<{}}  {:>9}  {:>9}  {:<{}}  {}\n", "topic", topic_width, "messages", "mean Hz",
             "type", type_width, "livod replays it as");
  for (const auto& t : topics) {
    // The mean rate over the whole bag (a topic's own span would need a pass over the data).
    const std::string rate =
        span_s > 0.0 ? fmt::format("{:.2f}", static_cast<double>(t.message_count) / span_s) : "-";
    std::string type = t.type;
    if (t.connection_count > 1) type += fmt::format(" ({} connections)", t.connection_count);
    fmt::print("  {:<{}}  {:>9}  {:>9}  {:<{}}  {}\n", t.topic, topic_width, t.message_count, rate,
               type, type_width, replayed_as(t.type));
  }
}

// ---------------------------------------------------------------------------------------------

struct Inspector {
  const char* name;
  bool (*matches)(std::span<const std::byte> head);
  void (*inspect)(const fs::path& path);
};

// First match wins. Recognisers look only at the first kHeadBytes bytes.
constexpr std::array kInspectors = {
    Inspector{"pcap/pcapng", is_capture, inspect_capture},
    Inspector{"ROS1 bag", is_bag, inspect_bag},
    Inspector{"candump log", is_candump, inspect_candump},
};

// Returns false if the file could not be inspected (the reason is printed).
bool inspect_file(const fs::path& path) {
  fmt::print("{}\n", path.string());
  try {
    const auto head = read_head(path);
    if (head.empty()) throw std::runtime_error(path.string() + ": empty file");
    for (const auto& inspector : kInspectors) {
      if (inspector.matches(head)) {
        inspector.inspect(path);
        return true;
      }
    }
    std::string known;
    for (const auto& inspector : kInspectors)
      known += (known.empty() ? "" : ", ") + std::string(inspector.name);
    std::fflush(stdout);  // keep the file name before its error on a shared terminal
    fmt::print(stderr, "livod inspect: {}: unrecognised file type (known: {})\n", path.string(),
               known);
  } catch (const std::exception& e) {
    std::fflush(stdout);
    fmt::print(stderr, "livod inspect: {}\n", e.what());
  }
  return false;
}

}  // namespace

void add_inspect_command(CLI::App& app, CommandContext& ctx) {
  auto files = std::make_shared<std::vector<std::string>>();
  auto* cmd = app.add_subcommand(
      "inspect",
      "Show what recorded files contain (pcap/pcapng captures, ROS1 bags, candump logs)");
  cmd->add_option("FILE", *files, "files to inspect")->required()->check(CLI::ExistingFile);
  cmd->callback([files, &ctx] {
    bool all_ok = true;
    for (std::size_t i = 0; i < files->size(); ++i) {
      if (i > 0) fmt::print("\n");
      all_ok = inspect_file((*files)[i]) && all_ok;
    }
    ctx.exit_code = all_ok ? 0 : 1;
  });
}

}  // namespace livod::daemon
