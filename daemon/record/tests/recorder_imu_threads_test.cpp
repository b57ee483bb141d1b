// External IMUs recorded through the recorder's taps, the way `livod record` and outputs.record
// record them: the live capture thread copies every CAN frame / serial read into the recorder's
// tap beside its ring to the scheduler; the recorder thread writes a candump log / a livod serial
// capture; the recording's config.yaml replays the file through the same decoder. The replay gives
// the same IMU samples as the live source did: values and sensor times exactly, host (receive)
// times moved by the recording's one offset onto UTC (a candump log keeps microseconds: the
// format's resolution).
//
// A serial IMU: a pseudo-terminal stands in for the serial line, opened by open_live_imu() as
// `livod run` opens it (the runtime plumbing). A CAN IMU: there is no CAN interface here (not even
// vcan), so a socketpair stands in for the CAN_RAW socket (CanSocket::adopt: the real receive
// code, kernel receive stamps) under the real CanImuSource capture thread.

#include <gtest/gtest.h>
#include <pty.h>
#include <sys/socket.h>
#include <unistd.h>

#include <chrono>
#include <filesystem>
#include <fstream>
#include <functional>
#include <mutex>
#include <string>
#include <thread>
#include <variant>
#include <vector>

#include "core/error.hpp"
#include "daemon/config/load_config.hpp"
#include "daemon/devices/imu_decoders.hpp"
#include "daemon/record/record_session.hpp"
#include "daemon/record/recorder.hpp"
#include "daemon/replay/sources.hpp"
#include "daemon/runtime/live_imu_source.hpp"
#include "drivers/imu/candump_frames.hpp"
#include "drivers/imu/imu_source.hpp"
#include "drivers/imu/sbg_can.hpp"
#include "drivers/imu/xsens_mtdata2.hpp"
#include "io/candump.hpp"
#include "io/serial_capture.hpp"
#include "tests/support/data_dir.hpp"

namespace livod::daemon::record {
namespace {

using namespace std::chrono_literals;

const std::string kExtrinsic =
    "    extrinsic: {translation: [0, 0, 0], rotation: {rpy_deg: [0, 0, 0]}}\n";
// The robot's LiDAR, recorded beside the IMU (its pcap stays empty here).
const std::string kLidar =
    "  - {name: vlp, driver: velodyne, model: VLP-16, source: {udp: {}},\n"
    "     extrinsic: {translation: [0, 0, 0], rotation: {rpy_deg: [0, 0, 0]}}}\n";

// Polls until `done` holds or `timeout` passes, pausing `pause` and then running `between` (a
// source's drain) each round. The caller asserts the outcome, with its own message.
void wait_until(std::chrono::milliseconds timeout, std::chrono::milliseconds pause,
                const std::function<bool()>& done, const std::function<void()>& between = {}) {
  const auto deadline = std::chrono::steady_clock::now() + timeout;
  while (!done() && std::chrono::steady_clock::now() < deadline) {
    std::this_thread::sleep_for(pause);
    if (between) between();
  }
}

LivodConfig load_file(const std::filesystem::path& path, const std::string& yaml) {
  std::ofstream(path) << yaml;
  ConfigResult loaded = load_config(path);
  for (const auto& p : loaded.problems) {
    EXPECT_NE(p.severity, Severity::error) << format_problem(loaded.source, p);
  }
  return loaded.config;
}

// Replays the recorded sensor as `livod replay --config DIR/config.yaml` opens it.
std::vector<ImuSample> replay_recorded(const std::filesystem::path& dir, const std::string& name,
                                       const std::filesystem::path& expected_file) {
  const ConfigResult recorded = load_config(dir / "config.yaml");
  for (const auto& p : recorded.problems) {
    EXPECT_NE(p.severity, Severity::error) << format_problem(recorded.source, p);
  }
  const SensorConfig* sensor = recorded.config.find_sensor(name);
  if (sensor == nullptr) {
    ADD_FAILURE() << "no sensor " << name << " in the recorded configuration";
    return {};
  }
  const auto* replay = std::get_if<ReplaySourceConfig>(&sensor->source);
  if (replay == nullptr) {
    ADD_FAILURE() << "the recorded sensor does not replay a file";
    return {};
  }
  EXPECT_EQ(replay->file, expected_file);
  auto source = replay::make_source(*sensor, *replay, {});
  std::vector<ImuSample> out;
  drivers::DecoderSinks sinks;
  sinks.on_imu = [&](const ImuSample& s) { out.push_back(s); };
  while (source->peek_time()) source->deliver(sinks);
  source->finish(sinks);
  return out;
}

void expect_same_samples(const std::vector<ImuSample>& live, const std::vector<ImuSample>& replayed,
                         std::int64_t offset_ns, std::int64_t resolution_ns) {
  ASSERT_EQ(replayed.size(), live.size());
  for (std::size_t k = 0; k < live.size(); ++k) {
    SCOPED_TRACE("sample " + std::to_string(k));
    EXPECT_EQ(replayed[k].stamp.sensor.ns, live[k].stamp.sensor.ns);
    const std::int64_t utc = live[k].stamp.host.ns + offset_ns;
    EXPECT_EQ(replayed[k].stamp.host.ns, utc - utc % resolution_ns);
    EXPECT_EQ(replayed[k].gyro_rad_s, live[k].gyro_rad_s);
    EXPECT_EQ(replayed[k].accel_m_s2, live[k].accel_m_s2);
  }
}

// Socketpairs handed out as the CAN interface (opened by the capture thread); the test writes
// frames into the peer end.
class FakeBus {
 public:
  ~FakeBus() {
    if (peer_ >= 0) ::close(peer_);
  }
  imu::CanSocket open() {
    int fds[2];
    if (::socketpair(AF_UNIX, SOCK_SEQPACKET, 0, fds) != 0) throw Error("socketpair failed");
    const std::lock_guard lock(mutex_);
    if (peer_ >= 0) ::close(peer_);
    peer_ = fds[1];
    return imu::CanSocket::adopt(fds[0], "can0");
  }
  void send(const imu::CanRecord& r) {
    const auto b = imu::serialize_can_frame(r);
    const std::lock_guard lock(mutex_);
    ASSERT_EQ(::write(peer_, b.data(), b.size()), static_cast<ssize_t>(b.size()));
  }

 private:
  std::mutex mutex_;
  int peer_ = -1;
};

TEST(RecordImu, ACanImuIsRecordedAsACandumpLogThatReplaysTheSameSamples) {
  const auto dir = test::temp_dir("record-can-imu");
  std::filesystem::remove_all(dir / "rec");
  const LivodConfig config =
      load_file(dir / "live.yaml", "body_frame: sbg\nsensors:\n" + kLidar + R"(  - name: sbg
    driver: can_imu
    source: {device: {interface: can0}}
    can: {decoder: sbg}
)" + kExtrinsic);
  EXPECT_TRUE(record_problems(config).empty());
  const SensorConfig& sensor = *config.find_sensor("sbg");
  ASSERT_TRUE(is_recorded(sensor));
  EXPECT_EQ(recorded_file_name(sensor), "sbg.log");

  RecordSession session(config, dir / "rec");
  session.recorder().add_packet_stream({"vlp", "lidar", 1206, 0});
  FakeBus bus;
  imu::CanImuSourceConfig c;
  c.name = "sbg";
  c.socket.interface = "can0";
  c.tap = &session.recorder().add_can_stream({"sbg", "can0"});
  imu::CanImuSource live(c, devices::make_can_imu_decoder(sensor.can, "sbg"),
                         [&bus] { return bus.open(); });
  session.start();

  constexpr int kSamples = 200;
  std::vector<ImuSample> captured;
  const auto poll = [&] { live.poll([&](const ImuSample& s) { captured.push_back(s); }); };
  for (int k = 0; k < kSamples; ++k) {
    const Eigen::Vector3d a(0.01 * k, -0.02 * k, 9.81);
    const Eigen::Vector3d g(0.001 * k, 0.0, -0.003 * k);
    for (const auto& f : imu::encode_sbg_sample(static_cast<std::uint32_t>(5000 * k), a, g, 25.0)) {
      bus.send(f);
    }
    if (k % 20 == 19) {
      std::this_thread::sleep_for(2ms);
      poll();
    }
  }
  wait_until(
      10s, 2ms, [&] { return captured.size() >= kSamples; }, poll);
  ASSERT_EQ(captured.size(), static_cast<std::size_t>(kSamples));
  live.stop();
  EXPECT_TRUE(session.finish().empty());

  const auto stats = session.recorder().stats().at(1);
  EXPECT_EQ(stats.file, dir / "rec" / "sbg.log");
  EXPECT_EQ(stats.unit, "frames");
  EXPECT_EQ(stats.packets, 3U * kSamples);
  EXPECT_EQ(stats.lost(), 0U);
  // A candump log that can-utils would read: "(seconds.micros) can0 ID#DATA" lines.
  io::CandumpReader reader(dir / "rec" / "sbg.log");
  io::CanFrame frame;
  std::size_t frames = 0;
  while (reader.next(frame)) {
    EXPECT_EQ(frame.interface, "can0");
    ++frames;
  }
  EXPECT_EQ(frames, 3U * kSamples);
  std::ifstream summary_file(dir / "rec" / "recording.txt");
  const std::string summary(std::istreambuf_iterator<char>(summary_file), {});
  EXPECT_NE(summary.find("sbg.log: 600 frames"), std::string::npos) << summary;

  const auto replayed = replay_recorded(dir / "rec", "sbg", dir / "rec" / "sbg.log");
  expect_same_samples(captured, replayed, session.recorder().realtime_offset_ns(), 1000);
}

TEST(RecordImu, ASerialImuIsRecordedAsASerialCaptureThatReplaysTheSameSamples) {
  const auto dir = test::temp_dir("record-serial-imu");
  std::filesystem::remove_all(dir / "rec");
  int master = -1;
  int slave = -1;
  ASSERT_EQ(::openpty(&master, &slave, nullptr, nullptr, nullptr), 0);
  const std::string tty = ::ttyname(slave);
  const LivodConfig config = load_file(
      dir / "live.yaml", "body_frame: mti\nsensors:\n" + kLidar +
                             "  - name: mti\n    driver: serial_imu\n"
                             "    source: {device: {path: " +
                             tty +
                             "}}\n"
                             "    serial: {protocol: xsens_mtdata2, baud_rate: 921600}\n" +
                             kExtrinsic);
  EXPECT_TRUE(record_problems(config).empty());
  const SensorConfig& sensor = *config.find_sensor("mti");
  EXPECT_EQ(recorded_file_name(sensor), "mti.serial");

  RecordSession session(config, dir / "rec");
  session.recorder().add_packet_stream({"vlp", "lidar", 1206, 0});
  // As `livod run` with outputs.record opens it.
  auto live = runtime::open_live_imu(sensor, config, nullptr, &session.recorder());
  session.start();
  ::close(slave);  // the source holds its own descriptor
  wait_until(5s, 10ms, [&] { return live->health(host_now())->device_state == "STREAMING"; });
  ASSERT_EQ(live->health(host_now())->device_state, "STREAMING");

  constexpr int kSamples = 120;
  std::vector<ImuSample> captured;
  drivers::DecoderSinks sinks;
  sinks.on_imu = [&](const ImuSample& s) { captured.push_back(s); };
  const auto drain = [&] {
    while (live->peek_time()) live->deliver(sinks);
  };
  // Bytes recorded so far (file 1: the IMU's; stats are published at every recorder turn).
  const auto recorded_bytes = [&] { return session.recorder().stats().at(1).payload_bytes; };
  std::uint64_t written = 0;
  for (int k = 0; k < kSamples; ++k) {
    imu::XsensSample x;
    x.packet_counter = static_cast<std::uint16_t>(k);
    x.sample_time_fine = static_cast<std::uint32_t>(25 * k);
    x.accel_m_s2 = Eigen::Vector3d(0.1 * k, 0.0, 9.81);
    x.gyro_rad_s = Eigen::Vector3d(0.01 * k, -0.002 * k, 0.0);
    const auto m = imu::encode_mtdata2_sample(x);
    // Messages torn across reads: the first part now, the rest with the next message.
    const std::size_t cut = k % 3 == 0 ? m.size() / 2 : m.size();
    ASSERT_EQ(::write(master, m.data(), cut), static_cast<ssize_t>(cut));
    written += cut;
    if (cut < m.size()) {
      // Everything up to the tear is read (and recorded) before the rest is written: waiting on
      // the recorder, not on a sleep, keeps every tear the end of a read on a loaded machine.
      wait_until(5s, 1ms, [&] { return recorded_bytes() >= written; });
      ASSERT_EQ(recorded_bytes(), written) << "message " << k << " torn";
      ASSERT_EQ(::write(master, m.data() + cut, m.size() - cut),
                static_cast<ssize_t>(m.size() - cut));
      written += m.size() - cut;
    }
    drain();
  }
  wait_until(
      10s, 2ms, [&] { return captured.size() >= kSamples; }, drain);
  ASSERT_EQ(captured.size(), static_cast<std::size_t>(kSamples));
  live->stop();
  EXPECT_TRUE(session.finish().empty());
  ::close(master);

  const auto stats = session.recorder().stats().at(1);
  EXPECT_EQ(stats.file, dir / "rec" / "mti.serial");
  EXPECT_EQ(stats.unit, "reads");
  EXPECT_GT(stats.packets, static_cast<std::uint64_t>(kSamples / 3)) << "torn reads recorded";
  EXPECT_EQ(stats.lost(), 0U);
  io::SerialCaptureReader reader(dir / "rec" / "mti.serial");
  io::SerialChunk chunk;
  std::int64_t previous = 0;
  while (reader.next(chunk)) {
    EXPECT_GE(chunk.rx_time_ns, previous);
    previous = chunk.rx_time_ns;
  }
  EXPECT_EQ(reader.chunks(), stats.packets);
  EXPECT_EQ(reader.bytes(), stats.payload_bytes);

  const auto replayed = replay_recorded(dir / "rec", "mti", dir / "rec" / "mti.serial");
  expect_same_samples(captured, replayed, session.recorder().realtime_offset_ns(), 1);
}

// A tap that overflows (the recorder thread not running: a disk that stalls) drops the newest
// frames and counts them per file and cause, without blocking the producer; what was queued is
// written.
TEST(RecordImu, AFullCanTapDropsAndCountsWithoutBlocking) {
  const auto dir = test::temp_dir("record-can-overflow");
  RecorderOptions options;
  options.dir = dir;
  options.stream_buffer_bytes = 1;  // the smallest tap: 256 frames
  Recorder recorder(options);
  auto& tap = recorder.add_can_stream({"mm7", "can1"});
  imu::CanRecord r;
  r.id = 0x174;
  r.len = 8;
  for (int k = 0; k < 1000; ++k) {
    r.rx_time_ns = 1'000'000'000 + k * 1'000'000;
    r.data[0] = static_cast<std::uint8_t>(k);
    tap.try_push(r);
  }
  recorder.start();
  recorder.stop();
  const auto stats = recorder.stats().at(0);
  EXPECT_EQ(stats.packets, 256U);
  EXPECT_EQ(stats.lost_buffer_full, 744U);
  ASSERT_EQ(stats.losses.size(), 1U);
  EXPECT_NE(stats.losses[0].reason.find("buffer full"), std::string::npos);
  EXPECT_NE(format_file_stats(stats).find("lost 744 frames (buffer full 744"), std::string::npos)
      << format_file_stats(stats);
  io::CandumpReader reader(dir / "mm7.log");
  io::CanFrame f;
  int k = 0;
  while (reader.next(f)) {
    EXPECT_EQ(f.interface, "can1");
    EXPECT_EQ(f.id, 0x174U);
    EXPECT_EQ(f.data[0], static_cast<std::uint8_t>(k));
    EXPECT_EQ(f.time_ns,
              1'000'000'000 + k * 1'000'000 + recorder.realtime_offset_ns() -
                  (1'000'000'000 + k * 1'000'000 + recorder.realtime_offset_ns()) % 1000);
    ++k;
  }
  EXPECT_EQ(k, 256);
}

// A serial capture killed mid-recording keeps every complete read: the recorder writes whole
// blocks; a block cut by the kill is reported as a truncated record at the end, after the reads
// before it.
TEST(RecordImu, ASerialCaptureReadsBackItsBlocksAndReportsACutTail) {
  const auto dir = test::temp_dir("record-serial-blocks");
  RecorderOptions options;
  options.dir = dir;
  options.block_bytes = 4096;
  Recorder recorder(options);
  auto& tap = recorder.add_serial_stream({"vn", 4096});
  std::vector<std::vector<std::byte>> reads;
  for (int k = 0; k < 100; ++k) {
    reads.emplace_back(static_cast<std::size_t>(1 + (k * 37) % 300),
                       static_cast<std::byte>(k & 0xFF));
    ASSERT_TRUE(tap.try_push(reads.back(), HostTime(2'000'000'000 + k * 500'000), 0));
  }
  recorder.start();
  recorder.stop();
  {
    io::SerialCaptureReader reader(dir / "vn.serial");
    io::SerialChunk chunk;
    std::size_t k = 0;
    while (reader.next(chunk)) {
      ASSERT_LT(k, reads.size());
      EXPECT_EQ(chunk.bytes, reads[k]);
      EXPECT_EQ(chunk.rx_time_ns, 2'000'000'000 + static_cast<std::int64_t>(k) * 500'000 +
                                      recorder.realtime_offset_ns());
      ++k;
    }
    EXPECT_EQ(k, reads.size());
  }
  // Cut inside the last record, as a kill during its block's write could leave it.
  std::filesystem::resize_file(dir / "vn.serial",
                               std::filesystem::file_size(dir / "vn.serial") - 5);
  io::SerialCaptureReader reader(dir / "vn.serial");
  io::SerialChunk chunk;
  std::size_t complete = 0;
  try {
    while (reader.next(chunk)) ++complete;
    ADD_FAILURE() << "the cut record was not reported";
  } catch (const FormatError& e) {
    EXPECT_NE(std::string(e.what()).find("truncated record"), std::string::npos) << e.what();
  }
  EXPECT_EQ(complete, reads.size() - 1);
}

}  // namespace
}  // namespace livod::daemon::record
