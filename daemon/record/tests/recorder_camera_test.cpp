// Cameras recorded through the recorder's taps as `livod record` and outputs.record record them:
// the camera's capture thread copies every frame it keeps into the recorder's frame tap beside its
// ring to the scheduler; the recorder thread maps it through its own camera clock and writes a
// lossless PNG and a data.csv row (EuRoC/ASL folder); the recording's config.yaml replays the
// folder. The replay gives the frames the live source delivered: the same pixels byte for byte,
// the same mid-exposure and exposure-start times (moved by the recording's one UTC offset), the
// same exposure.
//
// With Aravis's in-process fake camera (its real capture thread, GenICam device ticks: the
// free-running camera clock), and with frames pushed into a tap directly (mono8, mono16, BGR; a
// tap that overflows). Not a *_threads_test: GLib/Aravis are not instrumented for TSan.

#include <gtest/gtest.h>

#include <chrono>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <map>
#include <opencv2/core.hpp>
#include <opencv2/imgcodecs.hpp>
#include <string>
#include <thread>
#include <variant>
#include <vector>

#include "core/image.hpp"
#include "daemon/config/load_config.hpp"
#include "daemon/record/record_session.hpp"
#include "daemon/record/recorder.hpp"
#include "daemon/replay/sources.hpp"
#include "daemon/runtime/live_camera_source.hpp"
#include "daemon/runtime/sensor_clock.hpp"
#include "drivers/camera/aravis_camera.hpp"
#include "io/euroc.hpp"
#include "tests/support/data_dir.hpp"

namespace livod::daemon::record {
namespace {

using namespace std::chrono_literals;

const std::string kExtrinsic =
    "    extrinsic: {translation: [0, 0, 0], rotation: {rpy_deg: [0, 0, 0]}}\n";

bool same_pixels(const cv::Mat& a, const cv::Mat& b) {
  if (a.rows != b.rows || a.cols != b.cols || a.type() != b.type()) return false;
  for (int r = 0; r < a.rows; ++r) {
    if (std::memcmp(a.ptr(r), b.ptr(r), a.cols * a.elemSize()) != 0) return false;
  }
  return true;
}

TEST(RecordCamera, AnAravisCameraIsRecordedAsAnEurocFolderThatReplaysTheSameFrames) {
  camera::AravisCamera::enable_fake_interface();
  const auto dir = test::temp_dir("record-camera");
  std::filesystem::remove_all(dir / "rec");
  std::ofstream(dir / "live.yaml") << "body_frame: mti\nsensors:\n"
                                   << "  - {name: vlp, driver: velodyne, model: VLP-16, source: "
                                      "{udp: {}},\n"
                                   << "     extrinsic: {translation: [0, 0, 0], rotation: "
                                      "{rpy_deg: [0, 0, 0]}}}\n"
                                   << R"(  - name: mti
    driver: serial_imu
    source: {device: {path: /dev/ttyUSB0}}
    serial: {protocol: xsens_mtdata2}
)" << kExtrinsic << R"(  - name: cam
    driver: aravis
    source: {device: {camera_id: Fake_1}}
    time_offset_s: 0.003
    camera: {width: 320, height: 240, intrinsics: [300, 300, 160, 120], exposure_s: 0.004,
             frame_rate_hz: 50, pixel_format: mono8, buffers: 4}
)" << kExtrinsic;
  const ConfigResult loaded = load_config(dir / "live.yaml");
  for (const auto& p : loaded.problems) {
    EXPECT_NE(p.severity, Severity::error) << format_problem(loaded.source, p);
  }
  const LivodConfig& config = loaded.config;
  EXPECT_TRUE(record_problems(config).empty());
  const SensorConfig& sensor = *config.find_sensor("cam");
  ASSERT_TRUE(is_recorded(sensor));
  EXPECT_EQ(recorded_file_name(sensor), "cam");

  RecordSession session(config, dir / "rec");
  session.recorder().add_packet_stream({"vlp", "lidar", 1206, 0});
  session.recorder().add_serial_stream({"mti", 4096});
  // As `livod run` with outputs.record opens it.
  auto live = runtime::open_live_camera(sensor, config, nullptr, &session.recorder());
  session.start();
  std::vector<ImageFrame> delivered;
  drivers::DecoderSinks sinks;
  sinks.on_image = [&](const ImageFrame& f) { delivered.push_back(f); };
  const auto deadline = std::chrono::steady_clock::now() + 10s;
  while (delivered.size() < 30 && std::chrono::steady_clock::now() < deadline) {
    if (live->peek_time()) {
      live->deliver(sinks);
    } else {
      std::this_thread::sleep_for(2ms);
    }
  }
  ASSERT_GE(delivered.size(), 30U);
  live->stop();
  while (live->peek_time()) live->deliver(sinks);
  const auto live_health = live->health(host_now());
  EXPECT_TRUE(session.finish().empty());

  const auto stats = session.recorder().stats().at(2);
  EXPECT_EQ(stats.file, dir / "rec" / "cam");
  EXPECT_EQ(stats.unit, "frames");
  // Every frame the capture thread kept went to both sides, or was counted lost on one.
  EXPECT_EQ(stats.packets + stats.lost(),
            delivered.size() + live_health->streams.at(0).capture.ring_overruns);
  std::ifstream summary_file(dir / "rec" / "recording.txt");
  const std::string summary(std::istreambuf_iterator<char>(summary_file), {});
  EXPECT_NE(summary.find("cam: " + std::to_string(stats.packets) + " frames"), std::string::npos)
      << summary;

  // The recorded configuration replays the folder with the times as they are.
  const ConfigResult recorded = load_config(dir / "rec" / "config.yaml");
  for (const auto& p : recorded.problems) {
    EXPECT_NE(p.severity, Severity::error) << format_problem(recorded.source, p);
  }
  const SensorConfig* cam = recorded.config.find_sensor("cam");
  ASSERT_NE(cam, nullptr);
  const auto* replay = std::get_if<ReplaySourceConfig>(&cam->source);
  ASSERT_NE(replay, nullptr);
  EXPECT_EQ(replay->file, dir / "rec" / "cam");
  EXPECT_EQ(replay->format, ReplayFormat::euroc);
  EXPECT_EQ(cam->time_offset_s, 0.0);
  auto source = replay::make_source(*cam, *replay, {});
  runtime::SensorClockMapper clock(*cam);  // what the scheduler does with a replayed image
  std::vector<ImageFrame> replayed;
  sinks.on_image = [&](const ImageFrame& f) {
    ImageFrame mapped = f;
    clock.map_image(mapped);
    replayed.push_back(mapped);
  };
  while (source->peek_time()) source->deliver(sinks);
  ASSERT_EQ(replayed.size(), stats.packets);

  const std::int64_t offset = session.recorder().realtime_offset_ns();
  std::map<std::int64_t, const ImageFrame*> by_time;
  for (const auto& f : delivered) by_time[f.mid_exposure.ns + offset] = &f;
  std::size_t matched = 0;
  for (const auto& r : replayed) {
    const auto it = by_time.find(r.mid_exposure.ns);
    if (it == by_time.end()) continue;  // dropped on the live side (counted above)
    ++matched;
    const ImageFrame& l = *it->second;
    EXPECT_EQ(r.trigger_time.ns, l.trigger_time.ns + offset);
    EXPECT_EQ(r.exposure, l.exposure);
    EXPECT_EQ(r.exposure, 4ms);
    EXPECT_TRUE(same_pixels(r.image, l.image)) << "frame at " << r.mid_exposure.ns;
  }
  std::printf(
      "[record-camera] delivered %zu, recorded %llu (lost %llu), replayed %zu, matched %zu\n",
      delivered.size(), static_cast<unsigned long long>(stats.packets),
      static_cast<unsigned long long>(stats.lost()), replayed.size(), matched);
  EXPECT_EQ(matched, std::min<std::size_t>(replayed.size(), delivered.size()));
  if (stats.lost() == 0 && live_health->streams.at(0).capture.ring_overruns == 0) {
    EXPECT_EQ(matched, delivered.size());
  }
}

// Frames of each pixel format, pushed as a capture thread pushes them (host-monotonic stamps at
// the start of exposure): the folder holds them losslessly (16-bit and colour included), named by
// their mid-exposure time on the recording's clock; a tap that overflows drops the newest frames
// and counts them.
TEST(RecordCamera, EveryPixelFormatIsStoredLosslesslyAndAFullTapCountsItsDrops) {
  const auto dir = test::temp_dir("record-camera-formats");
  std::filesystem::remove_all(dir / "rec");
  RecorderOptions options;
  options.dir = dir / "rec";
  options.stream_buffer_bytes = 1;  // the smallest taps: 4 frames
  Recorder recorder(options);
  camera::CameraClockConfig clock;
  clock.time_offset = 3ms;
  struct Case {
    std::string name;
    camera::PixelFormat format;
  };
  const std::vector<Case> cases = {{"mono8", camera::PixelFormat::kMono8},
                                   {"mono16", camera::PixelFormat::kMono16},
                                   {"bgr8", camera::PixelFormat::kBgr8}};
  constexpr int kWidth = 64;
  constexpr int kHeight = 48;
  std::vector<camera::FrameRing*> taps;
  for (const auto& c : cases) {
    const std::size_t bytes = std::size_t{kWidth} * kHeight * camera::bytes_per_pixel(c.format);
    taps.push_back(&recorder.add_camera_stream({c.name, bytes, clock}));
  }
  cv::RNG rng(7);
  std::vector<std::vector<cv::Mat>> pushed(cases.size());
  for (std::size_t k = 0; k < cases.size(); ++k) {
    for (int i = 0; i < 6; ++i) {  // 4 fit, 2 are dropped
      cv::Mat image(kHeight, kWidth, camera::cv_type(cases[k].format));
      if (cases[k].format == camera::PixelFormat::kMono16) {
        rng.fill(image, cv::RNG::UNIFORM, 0, 65536);
      } else {
        rng.fill(image, cv::RNG::UNIFORM, 0, 256);
      }
      const std::span<std::byte> slot = taps[k]->begin_write();
      if (slot.empty()) continue;
      std::memcpy(slot.data(), image.data, image.total() * image.elemSize());
      camera::FrameInfo info;
      info.sequence = static_cast<std::uint64_t>(i);
      info.sensor_time = SensorTime(5'000'000'000 + i * 20'000'000);
      info.host_rx = HostTime(5'000'000'000 + i * 20'000'000 + 7'000'000);
      info.instant = camera::StampInstant::kStartOfExposure;
      info.clock = camera::CameraClockKind::kHostMonotonic;
      info.exposure = 2ms;
      info.width = kWidth;
      info.height = kHeight;
      info.format = cases[k].format;
      info.stride = static_cast<std::size_t>(image.step);
      taps[k]->commit(info);
      pushed[k].push_back(image);
    }
  }
  recorder.start();
  EXPECT_TRUE(!recorder.stop().empty()) << "the drops are reported";
  const auto stats = recorder.stats();
  ASSERT_EQ(stats.size(), cases.size());
  for (std::size_t k = 0; k < cases.size(); ++k) {
    SCOPED_TRACE(cases[k].name);
    EXPECT_EQ(stats[k].packets, 4U);
    EXPECT_EQ(stats[k].lost_buffer_full, 2U);
    ASSERT_EQ(pushed[k].size(), 4U);
    const auto folder = dir / "rec" / cases[k].name;
    std::ifstream csv_file(folder / "data.csv");
    const std::string csv(std::istreambuf_iterator<char>(csv_file), {});
    const auto rows = io::parse_euroc_camera_csv(csv, "data.csv", folder / "data");
    ASSERT_EQ(rows.size(), 4U);
    for (std::size_t i = 0; i < rows.size(); ++i) {
      // Host-monotonic start of exposure + 1 ms (half the exposure) + 3 ms time offset.
      EXPECT_EQ(rows[i].timestamp.ns, 5'000'000'000 + static_cast<std::int64_t>(i) * 20'000'000 +
                                          4'000'000 + recorder.realtime_offset_ns());
      ASSERT_TRUE(rows[i].exposure);
      EXPECT_EQ(*rows[i].exposure, 2ms);
      const cv::Mat png = cv::imread(rows[i].path.string(), cv::IMREAD_UNCHANGED);
      EXPECT_TRUE(same_pixels(png, pushed[k][i])) << rows[i].path;
    }
  }
}

}  // namespace
}  // namespace livod::daemon::record
