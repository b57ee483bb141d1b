// `livod decode CAPTURE.pcap --model MODEL [--calibration FILE] [--metadata FILE.json]
//  [--port N...] -o OUT.csv|OUT.pcd [--pcd-ascii]`: decodes a LiDAR capture with the driver the
// model names (drivers/registry) and writes every scan (drivers/scan_writer). Prints packet,
// scan, point, drop, gap and error counts. Exit codes: 0 done, 1 an unreadable capture or
// calibration, 2 a usage error (unknown model, unsupported output extension).
//
// --config is not offered yet: the YAML configuration loader (daemon/config) is being written;
// the decoder options it will carry (cut angle, range limits) have defaults meanwhile.

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
#include "drivers/registry.hpp"
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
  std::string config;  // optional livod configuration: supplies calibration / metadata files
};

// Takes the calibration/metadata of the configured LiDAR with the same model (explicit options
// win). Returns false after printing every problem when the configuration has errors.
bool apply_config(const std::string& path, const std::string& model, drivers::DecoderConfig& out) {
  const ConfigResult result = load_config(path);
  for (const auto& problem : result.problems) {
    fmt::print(stderr, "{}\n", format_problem(result.source, problem));
  }
  if (result.error_count() > 0) return false;
  const drivers::DecoderEntry* wanted = drivers::find_decoder(model);
  for (const auto& sensor : result.config.sensors) {
    if (!sensor.enabled || drivers::find_decoder(sensor.model) != wanted) continue;
    if (!out.calibration && !sensor.calibration.empty()) out.calibration = sensor.calibration;
    if (!out.metadata && !sensor.metadata.empty()) out.metadata = sensor.metadata;
    return true;
  }
  fmt::print(stderr, "livod decode: {} configures no enabled {} sensor; decoding with defaults\n",
             path, model);
  return true;
}

void print_family_details(const drivers::LidarDecoder& decoder) {
  if (const auto* v = dynamic_cast<const drivers::velodyne::VelodyneDecoder*>(&decoder)) {
    const auto& c = v->velodyne_counters();
    fmt::print(
        "velodyne: dropped returns {} (zero range {}, dual duplicates {}, out of range {}), "
        "late packets {}, factory byte mismatches {}, position packets {} (GPS fixes {}), "
        "hour rollovers {}, GPS time re-anchors {}\n",
        c.zero_ranges + c.duplicate_returns + c.out_of_range, c.zero_ranges, c.duplicate_returns,
        c.out_of_range, c.late_packets, c.factory_byte_mismatches, c.position_packets, c.gps_fixes,
        c.hour_rollovers, c.time_rebases);
  }
}

int run_decode(const DecodeArgs& args) {
  drivers::DecoderConfig config;
  config.model = args.model;
  if (!args.calibration.empty()) config.calibration = args.calibration;
  if (!args.metadata.empty()) config.metadata = args.metadata;
  if (drivers::find_decoder(args.model) == nullptr) {
    fmt::print(stderr, "livod decode: unknown model '{}'; known models: {}\n", args.model,
               drivers::known_models());
    return kExitUsage;
  }
  if (!args.config.empty() && !apply_config(args.config, args.model, config)) {
    return kExitFailure;
  }
  const auto format = drivers::scan_format_for(args.output, args.pcd_ascii);
  if (!format) {
    fmt::print(stderr, "livod decode: output must end in .csv or .pcd: {}\n", args.output);
    return kExitUsage;
  }

  try {
    const std::unique_ptr<drivers::LidarDecoder> decoder = drivers::make_decoder(config);
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
        "fragment sets; sequence gaps {}; decode errors {}\n",
        p.non_udp, p.malformed, p.filtered, p.incomplete_fragments, c.sequence_gaps,
        c.decode_errors);
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
  cmd->add_option("--model", args->model, "Sensor model: " + drivers::known_models())->required();
  cmd->add_option("--calibration", args->calibration,
                  "Velodyne calibration: VeloView XML or ROS/nebula YAML (default: the model's "
                  "nominal table)")
      ->check(CLI::ExistingFile);
  cmd->add_option("--metadata", args->metadata, "Ouster sensor metadata (JSON)")
      ->check(CLI::ExistingFile);
  cmd->add_option("--port", args->ports,
                  "UDP destination ports to decode (default: the sensor's data and IMU/position "
                  "ports)");
  cmd->add_option("-o,--output", args->output, "Output file: .csv or .pcd")->required();
  cmd->add_flag("--pcd-ascii", args->pcd_ascii, "Write the PCD as ASCII instead of binary");
  cmd->add_option("--config", args->config,
                  "livod configuration: the calibration/metadata files of its sensor with this "
                  "model are used (explicit --calibration/--metadata win)")
      ->check(CLI::ExistingFile);
  cmd->callback([&ctx, args] { ctx.exit_code = run_decode(*args); });
}

}  // namespace livod::daemon
