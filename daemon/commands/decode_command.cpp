// `livod decode CAPTURE.pcap --model MODEL [--calibration FILE] [--metadata FILE.json]
//  [--config C.yaml] [--port N...] -o OUT.csv|OUT.pcd [--pcd-ascii]`: decodes a LiDAR capture
// with the driver of the family that has the model (drivers/lidar_family.hpp) and writes every
// scan (drivers/scan_writer). Prints packet, scan, point, drop, gap and error counts. Exit codes:
// 0 done, 1 an unreadable capture, calibration or configuration, 2 a usage error (unknown model,
// unsupported output extension).

#include <fmt/core.h>
#include <CLI/CLI.hpp>

#include <cstdint>
#include <exception>
#include <filesystem>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "daemon/commands/command.hpp"
#include "daemon/config/load_config.hpp"
#include "daemon/config/problems.hpp"
#include "daemon/config/sensor_models.hpp"
#include "drivers/hesai/hesai_decoder.hpp"
#include "drivers/lidar_family.hpp"
#include "drivers/scan_writer.hpp"
#include "drivers/velodyne/velodyne_decoder.hpp"
#include "io/pcap.hpp"

namespace livod::daemon {
namespace {

constexpr int kExitFailure = 1;
constexpr int kExitUsage = 2;

struct DecodeArgs {
  std::string capture;
  std::string model;
  std::string calibration;
  std::string metadata;
  std::vector<std::uint16_t> ports;
  std::string output;
  bool pcd_ascii = false;
  std::string config;  // optional livod configuration: its sensor of this model supplies the rest
};

// The decoder configuration of the configured LiDAR with the same model (its files, frame cut
// and family section). Returns false after printing every problem when the configuration has
// errors; leaves `out` alone when no enabled sensor has the model.
bool apply_config(const std::string& path, const drivers::ModelMatch& wanted,
                  drivers::LidarDecoderConfig& out) {
  const ConfigResult result = load_config(path);
  for (const auto& problem : result.problems) {
    fmt::print(stderr, "{}\n", format_problem(result.source, problem));
  }
  if (result.error_count() > 0) return false;
  for (const auto& sensor : result.config.sensors) {
    if (!sensor.enabled || lidar_family(sensor.driver) != wanted.family) continue;
    const drivers::LidarModelInfo* model = wanted.family->find_model(sensor.model);
    // An Ouster sensor configured without a model matches any Ouster model.
    if (model != nullptr && model != wanted.model) continue;
    out = decoder_config(sensor);
    out.model = wanted.model->name;
    return true;
  }
  fmt::print(stderr, "livod decode: {} configures no enabled {} sensor; decoding with defaults\n",
             path, wanted.model->name);
  return true;
}

void print_family_details(const drivers::LidarDecoder& decoder) {
  if (const auto* v = dynamic_cast<const drivers::velodyne::VelodyneDecoder*>(&decoder)) {
    const auto& c = v->velodyne_counters();
    fmt::print(
        "velodyne: dropped returns {} (zero range {}, dual duplicates {}, out of range {}), "
        "late packets {}, factory byte mismatches {}, position packets {} (GPS fixes {}), "
        "hour rollovers {}, GPS time re-anchors {}, FOV boundary packets {}, undated blocks {}\n",
        c.zero_ranges + c.duplicate_returns + c.out_of_range, c.zero_ranges, c.duplicate_returns,
        c.out_of_range, c.late_packets, c.factory_byte_mismatches, c.position_packets, c.gps_fixes,
        c.hour_rollovers, c.time_rebases, c.fov_boundary_packets, c.undated_blocks);
  }
  if (const auto* h = dynamic_cast<const drivers::hesai::HesaiDecoder*>(&decoder)) {
    namespace hs = drivers::hesai;
    const auto& c = h->hesai_counters();
    std::string errors;
    for (std::size_t k = 1; k < c.packet_errors.size(); ++k) {
      if (c.packet_errors[k] == 0) continue;
      errors += fmt::format("{}{} {}", errors.empty() ? "" : ", ",
                            hs::to_string(static_cast<hs::PacketError>(k)), c.packet_errors[k]);
    }
    fmt::print(
        "hesai: dropped returns {} (zero range {}, dual duplicates {}, out of range {}), late "
        "packets {}, GPS packets {}, high-temperature packets {}, FOV boundary packets {}, motor "
        "{} RPM, return mode 0x{:02X}{}\n",
        c.zero_ranges + c.duplicate_returns + c.out_of_range, c.zero_ranges, c.duplicate_returns,
        c.out_of_range, c.late_packets, c.gps_packets, c.high_temperature_packets,
        c.fov_boundary_packets, c.motor_rpm, c.return_mode,
        errors.empty() ? std::string() : "; packet errors: " + errors);
  }
}

int run_decode(const DecodeArgs& args) {
  const auto match = drivers::find_model(args.model);
  if (!match) {
    fmt::print(stderr, "livod decode: unknown model '{}'; known models: {}\n", args.model,
               drivers::all_model_names());
    return kExitUsage;
  }
  drivers::LidarDecoderConfig config;
  config.model = match->model->name;
  if (!args.config.empty() && !apply_config(args.config, *match, config)) return kExitFailure;
  if (!args.calibration.empty()) config.calibration = args.calibration;
  if (!args.metadata.empty()) config.metadata = args.metadata;
  const auto format = drivers::scan_format_for(args.output, args.pcd_ascii);
  if (!format) {
    fmt::print(stderr, "livod decode: output must end in .csv or .pcd: {}\n", args.output);
    return kExitUsage;
  }

  try {
    const std::unique_ptr<drivers::LidarDecoder> decoder = match->family->make_decoder(config);
    io::PcapReader reader(args.capture);
    const std::vector<std::uint16_t> ports =
        args.ports.empty() ? decoder->default_ports() : args.ports;
    reader.set_port_filter(ports);
    drivers::ScanWriter writer(args.output, *format);

    drivers::DecoderSinks sinks;
    sinks.on_scan = [&writer](const LidarScan& scan) { writer.write(scan); };
    std::uint64_t imu_samples = 0;
    sinks.on_imu = [&imu_samples](const ImuSample&) { ++imu_samples; };
    while (const auto datagram = reader.next()) {
      decoder->on_packet(
          drivers::PacketView{datagram->payload, datagram->capture_time_ns, datagram->dst_port},
          sinks);
    }
    decoder->flush(sinks);
    writer.close();

    const auto& c = decoder->counters();
    const auto& p = reader.stats();
    std::string port_list;
    for (const auto port : ports)
      port_list += (port_list.empty() ? "" : ",") + std::to_string(port);
    fmt::print("{}: {} decoded as {} (ports {})\n", args.output, args.capture,
               decoder->model_name(), port_list);
    fmt::print(
        "packets {} (lidar {}, imu {}, other {}), scans {} ({} incomplete), points {}, "
        "imu samples {}\n",
        c.packets, c.lidar_packets, c.imu_packets, c.aux_packets, c.scans, c.incomplete_scans,
        writer.points_written(), imu_samples);
    fmt::print(
        "drops: capture records {} not UDP, {} malformed, {} on other ports, {} incomplete "
        "fragment sets; sequence gaps {}; decode errors {}; late points {}; sensor clock jumps "
        "{}\n",
        p.non_udp, p.malformed, p.filtered, p.incomplete_fragments, c.sequence_gaps,
        c.decode_errors, c.late_points, c.clock_jumps);
    print_family_details(*decoder);
    return 0;
  } catch (const std::exception& e) {
    fmt::print(stderr, "livod decode: {}\n", e.what());
    return kExitFailure;
  }
}

}  // namespace

void add_decode_command(CLI::App& app, CommandContext& ctx) {
  auto args = std::make_shared<DecodeArgs>();
  auto* cmd = app.add_subcommand("decode", "Decode a LiDAR capture (pcap) into points (CSV/PCD)");
  cmd->add_option("capture", args->capture, "pcap or pcapng capture")
      ->required()
      ->check(CLI::ExistingFile);
  cmd->add_option("--model", args->model, "Sensor model: " + drivers::all_model_names())
      ->required();
  cmd->add_option("--calibration", args->calibration,
                  "Velodyne calibration (VeloView XML or ROS/nebula YAML; default: the model's "
                  "nominal table) or Hesai angle correction file (CSV, required)")
      ->check(CLI::ExistingFile);
  cmd->add_option("--metadata", args->metadata, "Ouster sensor metadata (JSON)")
      ->check(CLI::ExistingFile);
  cmd->add_option("--port", args->ports,
                  "UDP destination ports to decode (default: the sensor's data and IMU/position "
                  "ports)");
  cmd->add_option("-o,--output", args->output, "Output file: .csv or .pcd")->required();
  cmd->add_flag("--pcd-ascii", args->pcd_ascii, "Write the PCD as ASCII instead of binary");
  cmd->add_option("--config", args->config,
                  "livod configuration: its sensor with this model supplies the calibration or "
                  "metadata file, the frame cut and the family section (explicit "
                  "--calibration/--metadata win)")
      ->check(CLI::ExistingFile);
  cmd->callback([&ctx, args] { ctx.exit_code = run_decode(*args); });
}

}  // namespace livod::daemon
