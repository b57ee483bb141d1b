// `livod decode CAPTURE.pcap --model MODEL [--calibration FILE] [--metadata FILE.json]
//  [--config C.yaml] [--port N...] -o OUT.csv|OUT.pcd [--pcd-ascii] [--accept-partial-input]`:
// decodes a LiDAR capture with the driver of the family that has the model
// (drivers/lidar_family.hpp; Ouster product names such as OS1-128 or OS-1-128 are checked
// against the metadata) and writes every scan (drivers/scan_writer). Prints packet, scan, point,
// drop, gap and error counts, and every stretch of the capture that could not be read. Exit
// codes: 0 done, 1 an unreadable capture, calibration or configuration, a model the metadata
// contradicts, or a decode that gave no point or more decode errors than packets (a wrong model,
// port or metadata), 2 a usage error (unknown model, unsupported output extension), 3 part of the
// capture could not be read (the output covers the rest) and --accept-partial-input was not given.

#include <fmt/core.h>
#include <CLI/CLI.hpp>

#include <algorithm>
#include <cstdint>
#include <exception>
#include <filesystem>
#include <map>
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
#include "io/input_loss.hpp"
#include "io/pcap.hpp"

namespace livod::daemon {
namespace {

constexpr std::size_t kPortsShown = 8;

struct DecodeArgs {
  std::string capture;
  std::string model;
  std::string calibration;
  std::string metadata;
  std::vector<std::uint16_t> ports;
  std::string output;
  bool pcd_ascii = false;
  bool accept_partial_input = false;
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

// Datagrams per destination port of the whole capture, most frequent first ("2368 x1000, ...").
std::string ports_in_capture(const std::string& capture) {
  io::PcapReader reader(capture);
  std::map<std::uint16_t, std::uint64_t> counts;
  while (const auto d = reader.next()) ++counts[d->dst_port];
  std::vector<std::pair<std::uint16_t, std::uint64_t>> sorted(counts.begin(), counts.end());
  std::stable_sort(sorted.begin(), sorted.end(),
                   [](const auto& a, const auto& b) { return a.second > b.second; });
  std::string out;
  for (std::size_t i = 0; i < sorted.size() && i < kPortsShown; ++i) {
    out += fmt::format("{}{} x{}", out.empty() ? "" : ", ", sorted[i].first, sorted[i].second);
  }
  return out.empty() ? "none" : out;
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

    int status = 0;
    const std::uint64_t points = writer.points_written();
    if (points == 0 || c.decode_errors > c.lidar_packets) {
      fmt::print(stderr,
                 "livod decode: {}: {} as {}: {} datagrams on ports {} gave {} lidar packets, {} "
                 "decode errors and {} points; datagrams per port in the capture: {}. Check "
                 "--model, --port{}\n",
                 args.capture, points == 0 ? "nothing decoded" : "mostly decode errors",
                 decoder->model_name(), p.udp_datagrams, port_list, c.lidar_packets,
                 c.decode_errors, points, ports_in_capture(args.capture),
                 decoder->model_name().starts_with("Ouster") || config.metadata
                     ? " and --metadata"
                     : " and --calibration");
      status = kExitFailure;
    }
    const io::InputLossLog& losses = reader.losses();
    for (const auto& loss : losses.entries()) {
      fmt::print(stderr, "livod decode: input lost: {}\n", io::format_loss(loss));
    }
    if (losses.not_listed() > 0) {
      fmt::print(stderr, "livod decode: input lost: {} more damaged stretches not listed\n",
                 losses.not_listed());
    }
    if (!losses.empty()) {
      fmt::print(stderr,
                 "livod decode: {} damaged stretch(es) skipped ({} bytes): {} covers only what "
                 "could be read{}\n",
                 losses.count(), losses.bytes(), args.output,
                 args.accept_partial_input ? "; partial input accepted (--accept-partial-input)"
                                           : "; --accept-partial-input accepts that");
      if (!args.accept_partial_input && status == 0) status = kExitPartialInput;
    }
    return status;
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
  cmd->add_option("--model", args->model,
                  "Sensor model: " + drivers::all_model_names() +
                      " (Ouster: OS for any, or the product name, e.g. OS1-128, checked against "
                      "the metadata)")
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
  cmd->add_flag("--accept-partial-input", args->accept_partial_input,
                "Exit 0 even when part of the capture could not be read (the losses are still "
                "printed); without it such a decode exits with status 3");
  cmd->add_option("--config", args->config,
                  "livod configuration: its sensor with this model supplies the calibration or "
                  "metadata file, the frame cut and the family section (explicit "
                  "--calibration/--metadata win)")
      ->check(CLI::ExistingFile);
  cmd->callback([&ctx, args] { ctx.exit_code = run_decode(*args); });
}

}  // namespace livod::daemon
