#include "daemon/record/record_session.hpp"

#include <yaml-cpp/yaml.h>

#include <algorithm>
#include <cstdio>
#include <ctime>
#include <set>
#include <variant>

#include <spdlog/spdlog.h>

#include "core/error.hpp"
#include "daemon/replay/decoder_factory.hpp"
#include "io/output_file.hpp"

namespace livod::daemon::record {
namespace {

std::string sensor_path(std::size_t i) {
  return "sensors[" + std::to_string(i) + "]";
}

ConfigProblem not_implemented(std::size_t i, const SensorConfig& s, std::string message) {
  ConfigProblem p;
  p.severity = Severity::error;
  p.kind = ProblemKind::not_implemented;
  p.path = sensor_path(i);
  p.line = s.line;
  p.message = "recording sensor '" + s.name + "' (" + std::string(enum_name(s.driver)) +
              "): " + std::move(message);
  return p;
}

std::string calibration_name(const SensorConfig& s) {
  return s.name + ".calibration" + s.calibration.extension().string();
}

// "2026-11-26T06:40:12.123Z" for a UTC time in ns.
std::string utc_text(std::int64_t ns) {
  const std::time_t seconds = static_cast<std::time_t>(ns / 1'000'000'000);
  std::tm tm{};
  gmtime_r(&seconds, &tm);
  char text[64];
  std::snprintf(text, sizeof(text), "%04d-%02d-%02dT%02d:%02d:%02d.%03dZ", tm.tm_year + 1900,
                tm.tm_mon + 1, tm.tm_mday, tm.tm_hour, tm.tm_min, tm.tm_sec,
                static_cast<int>((ns / 1'000'000) % 1000));
  return text;
}

}  // namespace

std::filesystem::path new_recording_folder(const std::filesystem::path& parent) {
  const std::time_t now = std::time(nullptr);
  std::tm tm{};
  gmtime_r(&now, &tm);
  char name[32];
  std::strftime(name, sizeof(name), "%Y%m%dT%H%M%SZ", &tm);
  std::filesystem::path folder = parent / name;
  for (int n = 2; std::filesystem::exists(folder); ++n) {
    folder = parent / (std::string(name) + "-" + std::to_string(n));
  }
  return folder;
}

bool is_recorded(const SensorConfig& sensor) {
  if (!sensor.enabled) return false;
  if (is_packet_lidar(sensor.driver)) return std::holds_alternative<UdpSourceConfig>(sensor.source);
  if (sensor.driver == Driver::can_imu || sensor.driver == Driver::serial_imu ||
      sensor.driver == Driver::v4l2 || sensor.driver == Driver::aravis) {
    return std::holds_alternative<DeviceSourceConfig>(sensor.source);
  }
  return false;
}

std::string recorded_file_name(const SensorConfig& sensor) {
  if (sensor.driver == Driver::can_imu) return sensor.name + ".log";
  if (sensor.driver == Driver::serial_imu) return sensor.name + ".serial";
  if (sensor.driver == Driver::v4l2 || sensor.driver == Driver::aravis) return sensor.name;
  return sensor.name + ".pcap";
}

std::vector<ConfigProblem> record_problems(const LivodConfig& config) {
  std::vector<ConfigProblem> out;
  for (std::size_t i = 0; i < config.sensors.size(); ++i) {
    const SensorConfig& s = config.sensors[i];
    if (!s.enabled) continue;
    if (std::holds_alternative<ReplaySourceConfig>(s.source)) {
      out.push_back(not_implemented(
          i, s, "it replays a recording: a recording is made from live sensors (copy the file)"));
      continue;
    }
    if (s.driver == Driver::can_imu || s.driver == Driver::serial_imu || s.driver == Driver::v4l2 ||
        s.driver == Driver::aravis) {
      continue;  // a device source (the configuration checks report any other)
    }
    if (!is_packet_lidar(s.driver)) {
      out.push_back(not_implemented(
          i, s,
          "livod records live packet LiDARs over UDP, cameras (EuRoC folders), CAN IMUs "
          "(candump logs) and serial IMUs (serial captures); this is none of them (disable the "
          "sensor to record the others)"));
      continue;
    }
    const auto* udp = std::get_if<UdpSourceConfig>(&s.source);
    if (udp == nullptr) continue;  // the configuration checks report it
    if (s.driver == Driver::ouster && s.metadata.empty() && udp->sensor_address.empty()) {
      // Live, the metadata comes from the sensor's HTTP API; the recording keeps it.
      out.push_back(not_implemented(
          i, s,
          "an Ouster recording replays only with its metadata: set `metadata:` (a saved file) or "
          "source.udp.sensor_address (livod fetches it from the sensor and saves it as " +
              s.name + ".json)"));
      continue;
    }
    // The replay of the recording filters the pcap on the driver's default ports (a replay
    // source cannot name ports yet): a LiDAR on other ports would replay nothing.
    std::vector<std::uint16_t> defaults;
    try {
      defaults = replay::make_lidar_decoder(s)->default_ports();
    } catch (const std::exception&) {
      continue;  // the decoder's own problem is reported by the file checks
    }
    std::vector<std::uint16_t> configured = {udp->ports.lidar, udp->ports.position};
    if (s.imu.enabled) configured.push_back(udp->ports.imu);
    for (const std::uint16_t port : configured) {
      if (port != 0 && std::find(defaults.begin(), defaults.end(), port) == defaults.end()) {
        out.push_back(not_implemented(
            i, s,
            "port " + std::to_string(port) +
                " is not one of the driver's default ports, and the replay of a recording reads "
                "the default ports only (a replay source cannot name ports yet)"));
        break;
      }
    }
  }
  return out;
}

std::vector<std::pair<std::filesystem::path, std::string>> recorded_files(
    const LivodConfig& config) {
  std::vector<std::pair<std::filesystem::path, std::string>> out;
  for (const SensorConfig& s : config.sensors) {
    if (!is_recorded(s)) continue;
    if (!s.metadata.empty()) out.emplace_back(s.metadata, s.name + ".json");
    if (!s.calibration.empty()) out.emplace_back(s.calibration, calibration_name(s));
  }
  return out;
}

std::string recorded_config_text(const LivodConfig& config,
                                 const std::vector<std::string>& not_recorded) {
  if (config.source_file.empty()) {
    throw Error("a recording rewrites the configuration file: load it from a file");
  }
  YAML::Node root = YAML::LoadFile(config.source_file.string());
  YAML::Node sensors = root["sensors"];
  for (std::size_t i = 0; sensors && i < sensors.size(); ++i) {
    YAML::Node node = sensors[i];
    const auto name = node["name"].as<std::string>("");
    const auto it = std::find_if(config.sensors.begin(), config.sensors.end(),
                                 [&](const SensorConfig& s) { return s.name == name; });
    if (it == config.sensors.end()) continue;
    const SensorConfig& s = *it;
    const bool left_out =
        std::find(not_recorded.begin(), not_recorded.end(), s.name) != not_recorded.end();
    if (left_out) node["enabled"] = false;  // no file holds it: the replay must not look for one
    if (is_recorded(s) && !left_out) {
      YAML::Node source;
      source["replay"]["file"] = recorded_file_name(s);
      if (sensor_kind(s.driver) == SensorKind::camera) {
        // The folder's times are the live mid-exposure times on the common timeline (the camera
        // clock and time_offset_s applied) of the frames the capture thread kept (decimation
        // applied): the replay takes them as they are.
        source["replay"]["format"] = "euroc";
        YAML::Node clock;
        clock["mode"] = "direct";
        node["clock"] = clock;
        node["time_offset_s"] = 0.0;
        if (YAML::Node camera = node["camera"]; camera && camera.IsMap()) camera["decimation"] = 1;
      }
      node["source"] = source;
      // An Ouster without a metadata file: the recorder saves what it fetches from the sensor.
      if (!s.metadata.empty() || s.driver == Driver::ouster) node["metadata"] = s.name + ".json";
      if (!s.calibration.empty()) node["calibration"] = calibration_name(s);
      continue;
    }
    // Not recorded (disabled): its files keep pointing at the originals.
    if (!s.metadata.empty()) node["metadata"] = s.metadata.string();
    if (!s.calibration.empty()) node["calibration"] = s.calibration.string();
    if (const auto* r = std::get_if<ReplaySourceConfig>(&s.source); r && node["source"]["replay"]) {
      node["source"]["replay"]["file"] = r->file.string();
    }
  }
  if (YAML::Node outputs = root["outputs"]; outputs && outputs.IsMap()) {
    for (const char* key : {"record", "trajectory", "map_pcd", "timing_report"}) {
      outputs.remove(key);
    }
  }
  YAML::Emitter emitter;
  emitter << root;
  return "# Written by `livod record` from " + config.source_file.string() +
         ": the recorded sensors\n# read their files in this folder. Replay with\n"
         "#   livod replay --config config.yaml -o OUT\n" +
         std::string(emitter.c_str()) + "\n";
}

RecordSession::RecordSession(const LivodConfig& config, std::filesystem::path dir,
                             RecorderOptions options)
    : dir_(std::move(dir)),
      recorder_([&] {
        if (std::filesystem::exists(dir_ / "config.yaml")) {
          throw Error(dir_.string() +
                      " already holds a recording (config.yaml): choose another "
                      "folder");
        }
        const auto problems = record_problems(config);
        if (!problems.empty()) throw Error(problems.front().message);
        options.dir = dir_;
        return options;
      }()),
      started_(host_now()) {
  for (const auto& [from, name] : recorded_files(config)) {
    std::error_code ec;
    std::filesystem::copy_file(from, dir_ / name, std::filesystem::copy_options::overwrite_existing,
                               ec);
    if (ec) throw Error("cannot copy " + from.string() + " into the recording: " + ec.message());
  }
  io::write_file(dir_ / "config.yaml", recorded_config_text(config));
  config_ = config;
}

void RecordSession::leave_out(const std::string& sensor, const std::string& reason) {
  if (recorder_.started()) throw Error("RecordSession: sensors are left out before start()");
  spdlog::warn("record: sensor '{}' is not recorded: {} (`livod record` records it)", sensor,
               reason);
  left_out_.push_back(sensor);
  io::write_file(dir_ / "config.yaml", recorded_config_text(config_, left_out_));
}

std::vector<std::string> RecordSession::finish() {
  if (finished_) return {};
  finished_ = true;
  std::vector<std::string> problems = recorder_.stop();
  const double seconds = to_seconds(host_now() - started_);
  std::string text = "# livod recording\nstarted " +
                     utc_text(started_.ns + recorder_.realtime_offset_ns()) + ", recorded for " +
                     std::to_string(static_cast<int>(seconds + 0.5)) + " s\n";
  for (const FileStats& s : recorder_.stats()) {
    text += "\n" + format_file_stats(s) + "\n";
    text += "  streams:";
    for (const auto& stream : s.streams) text += " " + stream;
    text += "\n";
    for (const auto& note : s.notes) text += "  " + note + "\n";
    if (s.first_ns != 0) {
      text += "  records from " + utc_text(s.first_ns) + " to " + utc_text(s.last_ns) + "\n";
    }
    for (const LossSpan& l : s.losses) {
      text += "  lost " + std::to_string(l.packets) + " " + s.unit + " from " +
              utc_text(l.first_ns) + " to " + utc_text(l.last_ns) + ": " + l.reason + "\n";
    }
  }
  try {
    io::write_file(dir_ / "recording.txt", text);
  } catch (const std::exception& e) {
    problems.push_back(e.what());
  }
  return problems;
}

}  // namespace livod::daemon::record
