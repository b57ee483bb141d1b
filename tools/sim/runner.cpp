#include "tools/sim/runner.hpp"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <fstream>
#include <iomanip>
#include <opencv2/core/mat.hpp>
#include <opencv2/imgcodecs.hpp>
#include <random>
#include <sstream>

#include "core/error.hpp"
#include "drivers/imu/bosch_mm7.hpp"
#include "drivers/imu/candump_frames.hpp"
#include "drivers/imu/sbg_can.hpp"
#include "drivers/imu/vectornav_binary.hpp"
#include "drivers/imu/xsens_mtdata2.hpp"
#include "drivers/lidar_family.hpp"
#include "io/candump.hpp"
#include "io/pcap.hpp"
#include "io/serial_capture.hpp"
#include "io/tum_writer.hpp"
#include "tools/sim/bag_output.hpp"
#include "tools/sim/lidar_registry.hpp"
#include "tools/sim/worlds.hpp"

namespace livod::sim {
namespace {

// Street ends: the world starts at x = -20 m (worlds.cpp) and the trajectory must stay this far
// from its end so that a LiDAR still sees buildings ahead.
constexpr double kStreetStartM = -20.0;
constexpr double kStreetAheadM = 60.0;
constexpr double kTrajectoryProbeS = 0.1;

World make_world(const Scenario& s, std::uint64_t seed) {
  WorldOptions options;
  options.foliage = s.scene.foliage;
  switch (s.world) {
    case WorldKind::kRoom:
      return make_room_world(seed, options);
    case WorldKind::kCorridor:
      return make_corridor_world();
    case WorldKind::kCorridorSideRooms:
      return make_corridor_side_rooms_world();
    case WorldKind::kStreet:
      return make_street_world(seed, s.street_length_m, options);
  }
  throw Error("unknown world kind");
}

std::int64_t to_ns(double seconds) {
  return static_cast<std::int64_t>(std::llround(seconds * 1e9));
}

// Derives independent, reproducible seeds for each sensor from the run seed and a name.
std::uint64_t sub_seed(std::uint64_t seed, const std::string& name) {
  std::uint64_t h = 1469598103934665603ULL ^ seed;
  for (const char c : name) {
    h ^= static_cast<std::uint8_t>(c);
    h *= 1099511628211ULL;
  }
  return h;
}

// Host clock stamps are integer ns: epoch + scenario time summed in double would round to the
// epoch's ulp (~240 ns at 1.7e9 s).
std::int64_t epoch_ns(double host_epoch_s) {
  return static_cast<std::int64_t>(std::llround(host_epoch_s * 1e9));
}

std::string yaml_vec(const Eigen::Vector3d& v) {
  std::ostringstream os;
  os << std::setprecision(12) << '[' << v.x() << ", " << v.y() << ", " << v.z() << ']';
  return os.str();
}

std::string yaml_matrix(const Eigen::Matrix3d& R) {
  std::ostringstream os;
  os << std::setprecision(12) << '[';
  for (int r = 0; r < 3; ++r) {
    for (int c = 0; c < 3; ++c) os << R(r, c) << (r == 2 && c == 2 ? "" : ", ");
  }
  os << ']';
  return os.str();
}

void write_extrinsic(std::ostream& os, const Eigen::Isometry3d& T) {
  os << "    extrinsic:\n"
     << "      translation: " << yaml_vec(T.translation()) << "\n"
     << "      rotation: {matrix: " << yaml_matrix(T.linear()) << "}\n";
}

// The configuration driver of a simulated model: its family's (drivers/lidar_family.hpp).
const drivers::LidarFamily& lidar_family_of(const std::string& model) {
  const auto match = drivers::find_model(model);
  if (!match) throw Error("no LiDAR family has the simulated model '" + model + "'");
  return *match->family;
}

// Simulated LiDAR datagrams arrive out of order when a delay spike holds one back; a capture is
// in arrival order, so pending datagrams are sorted and written once no later send can precede
// them (everything sent after `horizon_ns` arrives after it).
class OrderedPcapSink {
 public:
  explicit OrderedPcapSink(const std::filesystem::path& path) : writer_(path) {}
  void add(SimDatagram&& d) { pending_.push_back(std::move(d)); }
  void flush_until(std::int64_t horizon_ns) {
    std::stable_sort(
        pending_.begin(), pending_.end(),
        [](const SimDatagram& a, const SimDatagram& b) { return a.host_time_ns < b.host_time_ns; });
    std::size_t n = 0;
    while (n < pending_.size() && pending_[n].host_time_ns < horizon_ns) {
      const auto& d = pending_[n];
      writer_.write_udp(d.host_time_ns, d.src_ip, d.src_port, 0xC0A80132, d.dst_port, d.payload);
      ++n;
      ++written_;
    }
    pending_.erase(pending_.begin(), pending_.begin() + static_cast<std::ptrdiff_t>(n));
  }
  void finish() {
    flush_until(std::numeric_limits<std::int64_t>::max());
    writer_.flush();
  }
  [[nodiscard]] std::uint64_t written() const { return written_; }

 private:
  io::PcapWriter writer_;
  std::vector<SimDatagram> pending_;
  std::uint64_t written_ = 0;
};

void write_camera_yaml(const std::filesystem::path& path, const CameraMount& cam) {
  const auto& k = cam.params.intrinsics;
  std::ofstream os(path);
  os << std::setprecision(12);
  os << "# livod simulator camera (EuRoC/ASL sensor.yaml layout)\n"
     << "sensor_type: camera\ncomment: simulated global-shutter camera\n"
     << "T_BS:\n  cols: 4\n  rows: 4\n  data: [";
  const Eigen::Matrix4d T = cam.T_body_cam.matrix();
  for (int r = 0; r < 4; ++r) {
    for (int c = 0; c < 4; ++c) os << T(r, c) << (r == 3 && c == 3 ? "" : ", ");
  }
  os << "]\nrate_hz: " << cam.params.rate_hz << "\nresolution: [" << k.width << ", " << k.height
     << "]\ncamera_model: pinhole\nintrinsics: [" << k.fx << ", " << k.fy << ", " << k.cx << ", "
     << k.cy << "]\n"
     << "distortion_model: "
     << (k.model == CameraIntrinsics::Model::kEquidistant ? "equidistant" : "radial-tangential")
     << "\ndistortion_coefficients: [" << k.distortion[0] << ", " << k.distortion[1] << ", "
     << k.distortion[2] << ", " << k.distortion[3] << "]\n";
}

}  // namespace

std::uint64_t sensor_seed(std::uint64_t run_seed, const std::string& stream) {
  return sub_seed(run_seed, stream);
}

double street_length_for(const Scenario& scenario, double duration_s) {
  const Trajectory trajectory(scenario.trajectory);
  double max_x = 0.0;
  for (double t = 0.0; t <= duration_s + kTrajectoryProbeS; t += kTrajectoryProbeS) {
    max_x = std::max(max_x, trajectory.at(std::min(t, duration_s)).p_world.x());
  }
  return std::max(scenario.street_length_m, max_x + kStreetAheadM - kStreetStartM);
}

SimRunReport run_scenario(const Scenario& scenario, const SimRunOptions& options) {
  const auto wall_start = std::chrono::steady_clock::now();
  const double duration = options.duration_s.value_or(scenario.duration_s);
  if (!(std::isfinite(duration) && duration > 0.0 && duration <= kMaxSimDurationS)) {
    throw Error("simulation duration " + std::to_string(duration) +
                " s: must be a number of seconds in (0, " +
                std::to_string(static_cast<int>(kMaxSimDurationS)) + "]");
  }
  std::filesystem::create_directories(options.out_dir);
  Scenario sized = scenario;
  if (sized.world == WorldKind::kStreet)
    sized.street_length_m = street_length_for(scenario, duration);
  const World world = make_world(sized, options.seed);
  const MovingObjects movers =
      make_moving_objects(sized.world, sized.scene, options.seed, sized.street_length_m);
  const Trajectory trajectory(scenario.trajectory);
  const double epoch = options.host_epoch_s;
  const std::int64_t epoch_host_ns = epoch_ns(epoch);
  SequenceBagSpec bag;
  bag.host_epoch_ns = epoch_host_ns;
  SimRunReport report;
  report.simulated_s = duration;

  // LiDARs (each with its internal IMU) -> one pcap each.
  for (const auto& mount : scenario.lidars) {
    SimLidarOptions lo;
    lo.range = mount.range;
    lo.clock = mount.clock;
    lo.link = mount.link;
    lo.imu = mount.imu;
    lo.imu_noise = mount.imu_noise;
    lo.scan_rate_hz = mount.scan_rate_hz;
    lo.seed = sub_seed(options.seed, mount.name);
    lo.host_epoch_s = epoch;
    auto lidar = make_sim_lidar(mount.model, lo);
    SceneContext scene;
    scene.world = &world;
    scene.trajectory = &trajectory;
    scene.movers = &movers;
    scene.T_body_sensor = mount.T_body_sensor;
    const auto pcap_path = options.out_dir / (mount.name + ".pcap");
    OrderedPcapSink sink(pcap_path);
    SimOutputs out;
    out.on_datagram = [&sink](SimDatagram&& d) { sink.add(std::move(d)); };
    for (double t = 0.0; t < duration; t += options.chunk_s) {
      const double t_end = std::min(duration, t + options.chunk_s);
      lidar->run(t, t_end, scene, out);
      sink.flush_until(to_ns(epoch + t_end));
    }
    sink.finish();
    const auto side_files = lidar->write_side_files(options.out_dir, mount.name);
    report.sensors.push_back({mount.name, "lidar", sink.written(), 0, pcap_path});
    BagLidarSource bag_lidar{mount.name,   mount.model, pcap_path,
                             std::nullopt, mount.clock, mount.imu};
    // The one file beside the capture is what the family's decoder reads (metadata JSON or
    // angle correction CSV).
    if (!side_files.empty()) bag_lidar.decoder_file = side_files.front();
    bag.lidars.push_back(bag_lidar);
  }

  // CAN IMU -> candump log.
  if (scenario.can_imu) {
    const auto& mount = *scenario.can_imu;
    SensorClock clock(mount.clock, sub_seed(options.seed, mount.name + "/clock"));
    Link link(mount.link, sub_seed(options.seed, mount.name + "/link"));
    ImuModel imu(mount.noise, sub_seed(options.seed, mount.name + "/noise"));
    SceneContext scene;
    scene.world = &world;
    scene.trajectory = &trajectory;
    const auto log_path = options.out_dir / (mount.name + ".log");
    io::CandumpWriter writer(log_path);
    std::vector<io::CanFrame> pending;
    SimSensorReport rep{mount.name, "can_imu", 0, 0, log_path};
    const double period = 1.0 / mount.noise.rate_hz;
    constexpr double kFrameTime = 232e-6;  // 116 bits at 500 kbit/s per 8-byte frame
    const auto n_samples = static_cast<std::int64_t>(std::floor(duration / period));
    for (std::int64_t k = 0; k < n_samples; ++k) {
      const double t = static_cast<double>(k) * period;
      const ImuTruth m = imu.measure(scene.imu_truth(t, mount.T_body_imu));
      std::array<imu::CanRecord, 3> frames{};
      if (mount.format == CanImuFormat::kSbg) {
        const auto device_us = static_cast<std::uint32_t>(
            static_cast<std::uint64_t>(clock.stamp_ns(t) / 1000) & 0xFFFFFFFFULL);
        frames = imu::encode_sbg_sample(device_us, m.accel_m_s2, m.gyro_rad_s, 35.0);
      } else {
        // The MM7 has no clock; its 4-bit message counter counts samples.
        frames = imu::encode_bosch_mm7_sample(static_cast<std::uint8_t>(k & 0x0F), m.accel_m_s2,
                                              m.gyro_rad_s, 35.0);
      }
      const double delay = link.delay_s();
      if (delay < 0.0) {
        ++rep.dropped;
        continue;
      }
      for (std::size_t f = 0; f < frames.size(); ++f) {
        // candump logs have microsecond resolution.
        const double rx = epoch + t + delay + kFrameTime * static_cast<double>(f + 1);
        frames[f].rx_time_ns = static_cast<std::int64_t>(std::llround(rx * 1e6)) * 1000;
        pending.push_back(imu::to_candump_frame(frames[f], "can0"));
      }
    }
    std::stable_sort(
        pending.begin(), pending.end(),
        [](const io::CanFrame& a, const io::CanFrame& b) { return a.time_ns < b.time_ns; });
    for (const auto& f : pending) writer.write(f);
    writer.flush();
    rep.messages = pending.size();
    report.sensors.push_back(rep);
    bag.can_imu = BagCanImuSource{mount.name, log_path, mount.clock, mount.format};
  }

  // Serial IMU -> serial capture (the host's reads, torn messages and all).
  if (scenario.serial_imu) {
    const auto& mount = *scenario.serial_imu;
    SensorClock clock(mount.clock, sub_seed(options.seed, mount.name + "/clock"));
    ImuModel imu(mount.noise, sub_seed(options.seed, mount.name + "/noise"));
    std::mt19937_64 wire(sub_seed(options.seed, mount.name + "/wire"));
    SceneContext scene;
    scene.world = &world;
    scene.trajectory = &trajectory;
    const auto path = options.out_dir / (mount.name + ".serial");
    io::SerialCaptureWriter writer(path);
    SimSensorReport rep{mount.name, "serial_imu", 0, 0, path};
    const double period = 1.0 / mount.noise.rate_hz;
    const double byte_time = 10.0 / mount.baud_rate;  // start + 8 data + stop bits
    std::uniform_real_distribution<double> unit(0.0, 1.0);
    std::uniform_int_distribution<std::size_t> read_size(1, mount.max_read_bytes);
    // The line: every byte with the time its stop bit ends (scenario time).
    std::vector<std::pair<double, std::uint8_t>> line;
    double line_free = 0.0;
    const auto n_samples = static_cast<std::int64_t>(std::floor(duration / period));
    for (std::int64_t k = 0; k < n_samples; ++k) {
      const double t = static_cast<double>(k) * period;
      const ImuTruth m = imu.measure(scene.imu_truth(t, mount.T_body_imu));
      std::vector<std::uint8_t> bytes;
      if (mount.protocol == SerialImuProtocol::kVectorNavBinary) {
        // TimeStartup: ns of the sensor's clock, which does not run before its start.
        imu::VectorNavSample v;
        v.time_startup_ns =
            static_cast<std::uint64_t>(std::max<std::int64_t>(0, clock.stamp_ns(t)));
        v.accel_m_s2 = m.accel_m_s2;
        v.gyro_rad_s = m.gyro_rad_s;
        bytes = imu::encode_vectornav_sample(v);
      } else {
        imu::XsensSample x;
        x.packet_counter = static_cast<std::uint16_t>(k & 0xFFFF);
        x.sample_time_fine = static_cast<std::uint32_t>(
            static_cast<std::uint64_t>(clock.stamp_ns(t) / 100'000) & 0xFFFFFFFFULL);
        x.accel_m_s2 = m.accel_m_s2;
        x.gyro_rad_s = m.gyro_rad_s;
        bytes = imu::encode_mtdata2_sample(x);
      }
      if (unit(wire) < mount.corrupt_probability) {
        // One flipped bit past the header: the checksum fails and the sample is lost.
        bytes[bytes.size() - 1 - wire() % (bytes.size() - 5)] ^=
            static_cast<std::uint8_t>(1U << (wire() % 8));
        ++rep.dropped;
      }
      if (unit(wire) < mount.noise_probability) {
        const auto n = 1 + wire() % 8;
        std::vector<std::uint8_t> noise(n);
        for (auto& b : noise) b = static_cast<std::uint8_t>(wire());
        bytes.insert(bytes.begin(), noise.begin(), noise.end());
      }
      double at = std::max(t, line_free);
      for (const auto b : bytes) {
        at += byte_time;
        line.emplace_back(at, b);
      }
      line_free = at;
    }
    // The host's reads: random sizes, each returned a random latency after its last byte.
    std::exponential_distribution<double> latency(
        mount.read_latency_s > 0.0 ? 1.0 / mount.read_latency_s : 1e12);
    std::int64_t last_rx = 0;
    std::vector<std::byte> chunk;
    for (std::size_t i = 0; i < line.size();) {
      const std::size_t n = std::min(read_size(wire), line.size() - i);
      chunk.clear();
      for (std::size_t j = 0; j < n; ++j)
        chunk.push_back(static_cast<std::byte>(line[i + j].second));
      const double arrived = line[i + n - 1].first;
      const std::int64_t rx = std::max(last_rx, epoch_host_ns + to_ns(arrived + latency(wire)));
      writer.write(rx, chunk);
      last_rx = rx;
      i += n;
      ++rep.messages;
    }
    writer.flush();
    report.sensors.push_back(rep);
  }

  // Cameras -> EuRoC/ASL folders.
  for (const auto& cam : scenario.cameras) {
    const CameraSim sim(cam.params);
    const auto dir = options.out_dir / "mav0" / cam.name;
    std::filesystem::create_directories(dir / "data");
    std::ofstream csv(dir / "data.csv");
    csv << "#timestamp [ns],filename,exposure_ns\n";
    write_camera_yaml(dir / "sensor.yaml", cam);
    std::mt19937_64 rng(sub_seed(options.seed, cam.name));
    GreyImage img;
    SimSensorReport rep{cam.name, "camera", 0, 0, dir};
    const double period = 1.0 / cam.params.rate_hz;
    for (double t = period / 2; t < duration; t += period) {
      if (cam.params.in_outage(t)) continue;
      const double exposure = sim.exposure_at(t);
      const Eigen::Isometry3d T_world_cam = trajectory.at(t).T_world_body() * cam.T_body_cam;
      const std::int64_t stamp = epoch_host_ns + to_ns(t + cam.time_offset_s);
      const std::string file = std::to_string(stamp) + ".png";
      if (options.write_images) {
        sim.render(world, T_world_cam, exposure, rng, img, &movers, t);
        const cv::Mat mat(img.height, img.width, CV_8UC1, img.pixels.data());
        if (!cv::imwrite((dir / "data" / file).string(), mat)) {
          throw Error("cannot write image " + (dir / "data" / file).string());
        }
      }
      csv << stamp << ',' << file << ',' << to_ns(exposure) << '\n';
      ++rep.messages;
    }
    report.sensors.push_back(rep);
    bag.cameras.push_back({cam.name, dir});
  }

  // Ground truth of the body (IMU) frame on the host clock.
  {
    io::TumWriter gt(options.out_dir / "groundtruth.txt",
                     "timestamp tx ty tz qx qy qz qw  (livod sim: body/IMU frame in the world "
                     "frame, host clock)");
    const double period = 1.0 / scenario.groundtruth_rate_hz;
    const auto n = static_cast<std::int64_t>(std::floor(duration / period)) + 1;
    for (std::int64_t k = 0; k < n; ++k) {
      const double t = static_cast<double>(k) * period;
      const auto s = trajectory.at(t);
      gt.write(epoch_host_ns + to_ns(t), s.R_world_body, s.p_world);
      ++report.groundtruth_poses;
    }
    gt.close();
  }

  // A livod configuration that replays the outputs.
  {
    std::ofstream cfg(options.out_dir / "config.yaml");
    cfg << "# Generated by `livod sim --scenario " << scenario.name << " --seed " << options.seed
        << "`: replays this folder.\n";
    // The loader names a LiDAR's internal IMU "<lidar>.imu".
    const bool body_is_lidar_imu =
        std::any_of(scenario.lidars.begin(), scenario.lidars.end(),
                    [&](const LidarMount& l) { return l.name == scenario.body_imu; });
    cfg << "body_frame: " << scenario.body_imu << (body_is_lidar_imu ? ".imu" : "") << "\n";
    cfg << "sensors:\n";
    for (const auto& mount : scenario.lidars) {
      const drivers::LidarFamily& family = lidar_family_of(mount.model);
      cfg << "  - name: " << mount.name << "\n"
          << "    driver: " << family.driver << "\n"
          << "    model: " << mount.model << "\n"
          << "    source:\n      replay: {file: " << mount.name << ".pcap}\n";
      if (family.file == drivers::DecoderFile::kMetadata) {
        cfg << "    metadata: " << mount.name << ".json\n";
      } else if (family.file == drivers::DecoderFile::kCalibrationRequired) {
        cfg << "    calibration: " << mount.name << ".csv\n";
      }
      // Livox sensors stream without scans: the decoder cuts them every period.
      if ((family.driver == "livox_sdk1" || family.driver == "livox_sdk2") &&
          mount.scan_rate_hz != 10.0) {
        cfg << "    frame_cut: {mode: time, period_s: " << 1.0 / mount.scan_rate_hz << "}\n";
      }
      // Only the models with an internal IMU take the key (of the Velodynes, the HDL-32E).
      if (simulated_lidar_has_imu(mount.model)) {
        cfg << "    imu: {enabled: " << (mount.imu ? "true" : "false") << "}\n";
      }
      // Also when the body is this LiDAR's own IMU: the loader wants the LiDAR -> IMU extrinsic.
      write_extrinsic(cfg, mount.T_body_sensor);
    }
    if (scenario.can_imu) {
      const auto& imu = *scenario.can_imu;
      const bool sbg = imu.format == CanImuFormat::kSbg;
      cfg << "  - name: " << imu.name
          << "\n    driver: can_imu\n    model: " << (sbg ? "SBG" : "MM7.10") << "\n"
          << "    source:\n      replay: {file: " << imu.name << ".log}\n"
          << "    can: {decoder: " << (sbg ? "sbg" : "bosch_mm7") << "}\n";
      if (!sbg) {
        // No sensor clock: receive time minus the mean bus + link latency of TX1.
        const double latency = imu.link.delay_floor_s + imu.link.delay_mean_s + 232e-6;
        cfg << "    clock: {mode: receive_time, latency_s: " << latency << "}\n";
      }
      if (imu.name != scenario.body_imu) write_extrinsic(cfg, imu.T_body_imu);
    }
    if (scenario.serial_imu) {
      const auto& imu = *scenario.serial_imu;
      const bool xsens = imu.protocol == SerialImuProtocol::kXsensMtData2;
      cfg << "  - name: " << imu.name
          << "\n    driver: serial_imu\n    model: " << (xsens ? "MTi" : "VN-100") << "\n";
      // The estimator takes one IMU: a serial IMU beside another body IMU stays in the file,
      // disabled.
      if (imu.name != scenario.body_imu) {
        cfg << "    enabled: false  # not the body IMU (the estimator takes one IMU)\n";
      }
      cfg << "    source:\n      replay: {file: " << imu.name << ".serial}\n"
          << "    serial: {protocol: " << (xsens ? "xsens_mtdata2" : "vectornav_binary")
          << ", baud_rate: " << imu.baud_rate << "}\n";
      if (imu.name != scenario.body_imu) write_extrinsic(cfg, imu.T_body_imu);
    }
    for (const auto& cam : scenario.cameras) {
      const auto& k = cam.params.intrinsics;
      cfg << "  - name: " << cam.name << "\n    driver: v4l2\n    model: generic\n";
      // Without images (--no-images) the folder lists frames it does not have: the camera stays
      // in the file, disabled, so that the configuration replays as LiDAR-inertial.
      if (!options.write_images) cfg << "    enabled: false  # written with --no-images\n";
      cfg << "    source:\n      replay: {file: mav0/" << cam.name << "}\n"
          << "    camera: {model: "
          << (k.model == CameraIntrinsics::Model::kEquidistant ? "equidistant" : "pinhole")
          << ", width: " << k.width << ", height: " << k.height << ", intrinsics: [" << k.fx << ", "
          << k.fy << ", " << k.cx << ", " << k.cy << "], distortion: [" << k.distortion[0] << ", "
          << k.distortion[1] << ", " << k.distortion[2] << ", " << k.distortion[3] << "]}\n";
      write_extrinsic(cfg, cam.T_body_cam);
    }
    cfg << "outputs:\n  trajectory: trajectory.txt\n";
  }

  {
    std::ofstream info(options.out_dir / "scenario.txt");
    info << "scenario: " << scenario.name << "\n"
         << scenario.description << "\n"
         << "seed: " << options.seed << "\nduration_s: " << duration << "\n"
         << "host_epoch_s: " << std::setprecision(15) << epoch << "\n";
  }

  // Last: the bag transcodes the files written above.
  if (options.write_bag) {
    const auto bag_path = options.out_dir / "sequence.bag";
    const SequenceBagReport bag_report = write_sequence_bag(bag_path, bag);
    SimSensorReport rep{"bag", "bag", 0, 0, bag_path};
    for (const auto& topic : bag_report.topics) rep.messages += topic.messages;
    report.sensors.push_back(rep);
  }

  report.wall_s =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - wall_start).count();
  return report;
}

}  // namespace livod::sim
