// The recorder's IO thread on the real monterey HDL-32E capture (shared data), fed through its tap
// rings the way the capture threads feed them: what it writes is a classic pcap that livod's own
// reader (and Wireshark: valid Ethernet/IPv4/UDP with checksums) reads back datagram for datagram,
// with the receive times as record times and the streams merged in receive order; overflows of a
// tap are counted as losses, never block the producer; the recorded configuration points at the
// recording.

#include <gtest/gtest.h>

#include <fstream>
#include <string>
#include <vector>

#include "core/error.hpp"
#include "daemon/config/load_config.hpp"
#include "daemon/record/record_session.hpp"
#include "daemon/record/recorder.hpp"
#include "io/pcap.hpp"
#include "tests/support/data_dir.hpp"

namespace livod::daemon::record {
namespace {

constexpr const char* kMonterey = "velodyne/veloview/monterey-first-100-packets.pcap";

struct Datagram {
  std::int64_t time_ns = 0;
  std::uint32_t src_ip = 0;
  std::uint16_t src_port = 0;
  std::uint16_t dst_port = 0;
  std::vector<std::byte> payload;
  bool operator==(const Datagram&) const = default;
};

std::vector<Datagram> read_all(const std::filesystem::path& pcap, std::string* end_error = nullptr,
                               std::size_t* damaged = nullptr) {
  std::vector<Datagram> out;
  io::PcapReader reader(pcap);
  while (const auto d = reader.next()) {
    out.push_back({d->capture_time_ns, d->src_ip, d->src_port, d->dst_port,
                   std::vector<std::byte>(d->payload.begin(), d->payload.end())});
  }
  if (end_error != nullptr) *end_error = reader.end_error();
  if (damaged != nullptr) *damaged = reader.losses().count();
  return out;
}

// Pushes a datagram as a capture thread would: receive time on the monotonic clock.
bool push(drivers::capture::PacketRing& tap, const Datagram& d, std::int64_t offset_ns) {
  return tap.try_push(d.payload, HostTime(d.time_ns - offset_ns), d.dst_port, false, d.src_ip,
                      d.src_port);
}

TEST(Recorder, WritesEveryStreamOfALidarIntoOnePcapInReceiveOrder) {
  const auto capture = read_all(test::data_path(kMonterey));
  ASSERT_EQ(capture.size(), 3001U);
  const auto dir = test::temp_dir("recorder-order");
  RecorderOptions options;
  options.dir = dir;
  options.block_bytes = 256 * 1024;
  Recorder recorder(options);
  auto& data = recorder.add_packet_stream({"hdl", "lidar", 1206, 0x7F000001});
  auto& position = recorder.add_packet_stream({"hdl", "position", 512, 0x7F000001});
  // Every datagram is queued before the thread starts: the recorder, not the order of the
  // pushes, must interleave the two ports by receive time.
  for (const auto& d : capture) {
    ASSERT_TRUE(push(d.dst_port == 8308 ? position : data, d, recorder.realtime_offset_ns()));
  }
  recorder.start();
  const auto problems = recorder.stop();
  EXPECT_TRUE(problems.empty()) << problems.front();

  std::string end_error;
  std::size_t damaged = 0;
  const auto recorded = read_all(dir / "hdl.pcap", &end_error, &damaged);
  EXPECT_TRUE(end_error.empty()) << end_error;
  EXPECT_EQ(damaged, 0U);
  ASSERT_EQ(recorded.size(), capture.size());
  for (std::size_t i = 0; i < capture.size(); ++i) {
    ASSERT_EQ(recorded[i], capture[i]) << "datagram " << i;
  }
  const auto stats = recorder.stats();
  ASSERT_EQ(stats.size(), 1U);
  EXPECT_EQ(stats[0].packets, 3001U);
  EXPECT_EQ(stats[0].lost(), 0U);
  EXPECT_EQ(stats[0].file_bytes, std::filesystem::file_size(dir / "hdl.pcap"));
  EXPECT_EQ(stats[0].first_ns, capture.front().time_ns);
  EXPECT_EQ(stats[0].last_ns, capture.back().time_ns);

  // A file cut inside its last record (a process killed while the kernel took a block): every
  // record before reads back, the tail is reported as truncated, not as an error mid-file.
  const auto cut = dir / "cut.pcap";
  std::filesystem::copy_file(dir / "hdl.pcap", cut);
  std::filesystem::resize_file(cut, std::filesystem::file_size(cut) - 100);
  const auto survived = read_all(cut, &end_error, &damaged);
  EXPECT_EQ(survived.size(), capture.size() - 1);
  EXPECT_NE(end_error.find("truncated"), std::string::npos) << end_error;
  EXPECT_EQ(damaged, 1U);
}

TEST(Recorder, ATapThatOverflowsDropsAndCountsWithoutBlockingTheProducer) {
  const auto capture = read_all(test::data_path(kMonterey));
  const auto dir = test::temp_dir("recorder-overflow");
  RecorderOptions options;
  options.dir = dir;
  options.stream_buffer_bytes = 1;  // the smallest tap: 256 packets
  Recorder recorder(options);
  auto& data = recorder.add_packet_stream({"hdl", "lidar", 1206, 0});
  std::size_t accepted = 0;
  std::vector<Datagram> data_packets;
  for (const auto& d : capture) {
    if (d.dst_port != 2368) continue;
    data_packets.push_back(d);
    if (push(data, d, recorder.realtime_offset_ns())) ++accepted;
  }
  EXPECT_EQ(accepted, 256U);
  recorder.start();
  const auto problems = recorder.stop();
  ASSERT_EQ(problems.size(), 1U);
  EXPECT_NE(problems[0].find("buffer full " + std::to_string(data_packets.size() - 256)),
            std::string::npos)
      << problems[0];
  const auto stats = recorder.stats().at(0);
  EXPECT_EQ(stats.packets, 256U);
  EXPECT_EQ(stats.lost_buffer_full, data_packets.size() - 256);
  ASSERT_EQ(stats.losses.size(), 1U);
  EXPECT_EQ(stats.losses[0].packets, data_packets.size() - 256);
  const auto recorded = read_all(dir / "hdl.pcap");
  ASSERT_EQ(recorded.size(), 256U);
  EXPECT_TRUE(std::equal(recorded.begin(), recorded.end(), data_packets.begin()));
}

TEST(Recorder, ADatagramCutByItsSlotIsCountedNotWritten) {
  const auto dir = test::temp_dir("recorder-truncated");
  RecorderOptions options;
  options.dir = dir;
  Recorder recorder(options);
  auto& tap = recorder.add_packet_stream({"s", "lidar", 100, 0});
  const std::vector<std::byte> small(50, std::byte{1});
  const std::vector<std::byte> large(150, std::byte{2});
  ASSERT_TRUE(tap.try_push(small, HostTime(1'000'000'000), 2368));
  ASSERT_TRUE(tap.try_push(large, HostTime(1'001'000'000), 2368));
  ASSERT_TRUE(tap.try_push(small, HostTime(1'002'000'000), 2368));
  recorder.start();
  recorder.stop();
  const auto stats = recorder.stats().at(0);
  EXPECT_EQ(stats.packets, 2U);
  EXPECT_EQ(stats.lost_truncated, 1U);
  EXPECT_EQ(read_all(dir / "s.pcap").size(), 2U);
}

TEST(RecordSession, WritesAConfigurationThatReplaysTheRecordingAndRefusesToOverwriteIt) {
  const auto dir = test::temp_dir("record-session");
  const auto calibration = test::data_path("velodyne/veloview/HDL-32.xml");
  const auto config_path = dir / "live.yaml";
  std::ofstream(config_path) << "# the robot\nbody_frame: hdl.imu\nsensors:\n"
                             << "  - name: hdl\n    driver: velodyne\n    model: HDL-32E\n"
                             << "    calibration: " << calibration << "\n"
                             << "    source: {udp: {bind_address: 127.0.0.1}}\n"
                             << "    extrinsic: {translation: [0, 0, 0], rotation: {rpy_deg: [0, "
                                "0, 0]}}\n"
                             << "outputs:\n  trajectory: t.txt\n  record: rec\n";
  const ConfigResult loaded = load_config(config_path);
  ASSERT_TRUE(loaded.ok());
  EXPECT_EQ(loaded.config.outputs.record, dir / "rec");
  EXPECT_TRUE(record_problems(loaded.config).empty());
  {
    RecordSession session(loaded.config, dir / "rec");
    session.recorder().add_packet_stream({"hdl", "lidar", 1206, 0});
    session.start();
    EXPECT_TRUE(session.finish().empty());
  }
  EXPECT_TRUE(std::filesystem::exists(dir / "rec" / "hdl.pcap"));
  EXPECT_TRUE(std::filesystem::exists(dir / "rec" / "recording.txt"));
  // The copied calibration, the pcap as the source, no outputs that would write elsewhere.
  const ConfigResult recorded = load_config(dir / "rec" / "config.yaml");
  for (const auto& p : recorded.problems) ADD_FAILURE() << p.message;
  ASSERT_TRUE(recorded.ok());
  const SensorConfig& s = recorded.config.sensors.at(0);
  const auto* replay = std::get_if<ReplaySourceConfig>(&s.source);
  ASSERT_NE(replay, nullptr);
  EXPECT_EQ(replay->file, dir / "rec" / "hdl.pcap");
  EXPECT_EQ(s.calibration, dir / "rec" / "hdl.calibration.xml");
  EXPECT_EQ(std::filesystem::file_size(s.calibration), std::filesystem::file_size(calibration));
  EXPECT_TRUE(recorded.config.outputs.record.empty());
  EXPECT_TRUE(recorded.config.outputs.trajectory.empty());
  // The folder holds a recording now: a session refuses it; `livod run` records into new
  // subfolders of outputs.record.
  EXPECT_THROW(RecordSession(loaded.config, dir / "rec"), livod::Error);
  const auto first = new_recording_folder(dir / "rec");
  EXPECT_EQ(first.parent_path(), dir / "rec");
  EXPECT_EQ(first.filename().string().size(), 16U) << first;  // 20261126T071203Z
  std::filesystem::create_directories(first);
  EXPECT_EQ(new_recording_folder(dir / "rec").filename().string().substr(0, 16),
            first.filename().string());
  EXPECT_NE(new_recording_folder(dir / "rec"), first);
}

// `livod run` opens only the sensors the estimator uses (no camera with the visual update off):
// one it leaves out is disabled in the recording's configuration, which then loads without
// looking for a file the recording does not hold.
TEST(RecordSession, ASensorLeftOutIsDisabledInTheRecordedConfiguration) {
  const auto dir = test::temp_dir("record-left-out");
  std::filesystem::remove_all(dir / "rec");
  const auto config_path = dir / "live.yaml";
  std::ofstream(config_path) << "body_frame: hdl.imu\nsensors:\n"
                             << "  - name: hdl\n    driver: velodyne\n    model: HDL-32E\n"
                             << "    source: {udp: {bind_address: 127.0.0.1}}\n"
                             << "    extrinsic: {translation: [0, 0, 0], rotation: {rpy_deg: [0, "
                                "0, 0]}}\n"
                             << "  - name: cam\n    driver: v4l2\n"
                             << "    source: {device: {path: /dev/video0}}\n"
                             << "    camera: {width: 640, height: 480, intrinsics: [500, 500, "
                                "320, 240]}\n"
                             << "    extrinsic: {translation: [0, 0, 0], rotation: {rpy_deg: [0, "
                                "0, 0]}}\n"
                             << "estimator: {vio: {enabled: false}}\n";
  const ConfigResult loaded = load_config(config_path);
  ASSERT_TRUE(loaded.ok());
  EXPECT_TRUE(record_problems(loaded.config).empty());
  {
    RecordSession session(loaded.config, dir / "rec");
    session.recorder().add_packet_stream({"hdl", "lidar", 1206, 0});
    session.leave_out("cam", "not used");
    session.start();
    EXPECT_THROW(session.leave_out("cam", "too late"), livod::Error);
    EXPECT_TRUE(session.finish().empty());
  }
  const ConfigResult recorded = load_config(dir / "rec" / "config.yaml");
  for (const auto& p : recorded.problems) {
    EXPECT_NE(p.severity, Severity::error) << format_problem(recorded.source, p);
  }
  const SensorConfig* cam = recorded.config.find_sensor("cam");
  ASSERT_NE(cam, nullptr);
  EXPECT_FALSE(cam->enabled);
  EXPECT_TRUE(std::holds_alternative<DeviceSourceConfig>(cam->source));
  EXPECT_FALSE(std::filesystem::exists(dir / "rec" / "cam"));
  EXPECT_TRUE(
      std::holds_alternative<ReplaySourceConfig>(recorded.config.find_sensor("hdl")->source));
}

TEST(RecordSession, SensorsThatCannotBeRecordedAreNotImplementedErrors) {
  const auto dir = test::temp_dir("record-problems");
  const auto config_path = dir / "live.yaml";
  std::ofstream(config_path)
      << "body_frame: os1.imu\nsensors:\n"
      << "  - name: os1\n    driver: ouster\n    model: OS1-64\n"
      << "    source: {udp: {}}\n"  // no metadata file and nowhere to fetch it from
      << "    extrinsic: {translation: [0, 0, 0], rotation: {rpy_deg: [0, 0, 0]}}\n"
      << "  - name: hdl\n    driver: velodyne\n    model: VLP-16\n"
      << "    source: {udp: {ports: {lidar: 2370}}}\n"
      << "    extrinsic: {translation: [0, 0, 0], rotation: {rpy_deg: [0, 0, 0]}}\n"
      << "  - name: mti\n    driver: serial_imu\n    source: {device: {path: /dev/ttyUSB0}}\n"
      << "    serial: {protocol: xsens_mtdata2}\n"
      << "    extrinsic: {translation: [0, 0, 0], rotation: {rpy_deg: [0, 0, 0]}}\n"
      << "  - name: sbg\n    driver: can_imu\n    source: {device: {interface: can0}}\n"
      << "    can: {decoder: sbg}\n"
      << "    extrinsic: {translation: [0, 0, 0], rotation: {rpy_deg: [0, 0, 0]}}\n"
      << "  - name: rec\n    driver: can_imu\n    source: {replay: {file: old.log}}\n"
      << "    can: {decoder: sbg}\n"
      << "    extrinsic: {translation: [0, 0, 0], rotation: {rpy_deg: [0, 0, 0]}}\n";
  const ConfigResult loaded = load_config(config_path);
  // (The configuration itself may have its own problems, e.g. a second LiDAR; the recording's
  // are what matter here.)
  // The IMUs with a device source are recorded (candump log, serial capture); a sensor that
  // replays a file is not.
  const auto problems = record_problems(loaded.config);
  ASSERT_EQ(problems.size(), 3U);
  for (const auto& p : problems) EXPECT_EQ(p.kind, ProblemKind::not_implemented);
  EXPECT_NE(problems[0].message.find("metadata"), std::string::npos) << problems[0].message;
  EXPECT_NE(problems[1].message.find("port 2370"), std::string::npos) << problems[1].message;
  EXPECT_NE(problems[2].message.find("'rec'"), std::string::npos) << problems[2].message;
  EXPECT_NE(problems[2].message.find("replays a recording"), std::string::npos)
      << problems[2].message;
}

}  // namespace
}  // namespace livod::daemon::record
