#include "daemon/replay/input_assignment.hpp"

#include <algorithm>
#include <cctype>
#include <map>

#include "core/error.hpp"

namespace livod::daemon::replay {
namespace {

std::optional<ReplayFormat> format_of(const std::filesystem::path& path) {
  if (std::filesystem::is_directory(path)) return ReplayFormat::euroc;
  std::string ext = path.extension().string();
  std::transform(ext.begin(), ext.end(), ext.begin(),
                 [](unsigned char c) { return static_cast<char>(std::tolower(c)); });
  if (ext == ".pcap" || ext == ".pcapng") return ReplayFormat::pcap;
  if (ext == ".log" || ext == ".candump") return ReplayFormat::candump;
  if (ext == ".bag") return ReplayFormat::rosbag1;
  if (ext == ".serial") return ReplayFormat::serial;
  return std::nullopt;
}

// Sensors a bare path of this format goes to.
bool takes(const SensorConfig& sensor, ReplayFormat format) {
  if (!sensor.enabled) return false;
  switch (format) {
    case ReplayFormat::pcap:
      return is_packet_lidar(sensor.driver);
    case ReplayFormat::candump:
      return sensor.driver == Driver::can_imu;
    case ReplayFormat::rosbag1: {
      const auto* r = std::get_if<ReplaySourceConfig>(&sensor.source);
      return r != nullptr && r->format == ReplayFormat::rosbag1;
    }
    case ReplayFormat::euroc:
      return sensor_kind(sensor.driver) == SensorKind::camera;
    case ReplayFormat::serial:
      return sensor.driver == Driver::serial_imu;
  }
  return false;
}

SensorRecording recording_for(const SensorConfig& sensor, const std::filesystem::path& file,
                              ReplayFormat format) {
  SensorRecording r;
  r.replay.file = file;
  r.replay.format = format;
  r.from_command_line = true;
  if (const auto* configured = std::get_if<ReplaySourceConfig>(&sensor.source)) {
    r.replay.topic = configured->topic;
  }
  if (const auto* udp = std::get_if<UdpSourceConfig>(&sensor.source)) {
    for (const std::uint16_t port : {udp->ports.lidar, udp->ports.imu, udp->ports.position}) {
      if (port != 0 && std::find(r.ports.begin(), r.ports.end(), port) == r.ports.end()) {
        r.ports.push_back(port);
      }
    }
  }
  if (format == ReplayFormat::rosbag1 && r.replay.topic.empty()) {
    throw Error("sensor '" + sensor.name + "': a bag needs the topic to read; configure it as " +
                "source: {replay: {file: ..., topic: ...}}");
  }
  return r;
}

}  // namespace

std::vector<std::optional<SensorRecording>> assign_recordings(
    const LivodConfig& config, const std::vector<std::string>& inputs) {
  const auto& sensors = config.sensors;
  std::vector<std::optional<SensorRecording>> out(sensors.size());
  for (std::size_t i = 0; i < sensors.size(); ++i) {
    if (const auto* r = std::get_if<ReplaySourceConfig>(&sensors[i].source)) {
      out[i] = SensorRecording{*r, {}, false};
    }
  }

  std::vector<bool> named(sensors.size(), false);
  std::map<ReplayFormat, std::vector<std::filesystem::path>> bare;
  for (const auto& input : inputs) {
    const auto eq = input.find('=');
    const bool has_name = eq != std::string::npos && eq > 0 &&
                          std::none_of(input.begin(), input.begin() + static_cast<long>(eq),
                                       [](char c) { return c == '/' || c == '.'; });
    const std::filesystem::path path = has_name ? input.substr(eq + 1) : input;
    if (!std::filesystem::exists(path)) throw Error("input '" + path.string() + "' does not exist");
    const auto format = format_of(path);
    if (!format) {
      throw Error("input '" + path.string() +
                  "': unknown format (.pcap, .pcapng, .log, .candump, .bag, .serial or a folder)");
    }
    if (has_name) {
      const std::string name = input.substr(0, eq);
      const auto it = std::find_if(sensors.begin(), sensors.end(),
                                   [&](const SensorConfig& s) { return s.name == name; });
      if (it == sensors.end()) throw Error("input '" + input + "': no sensor named '" + name + "'");
      const auto i = static_cast<std::size_t>(it - sensors.begin());
      out[i] = recording_for(*it, path, *format);
      named[i] = true;
    } else {
      bare[*format].push_back(path);
    }
  }

  for (const auto& [format, paths] : bare) {
    if (paths.size() > 1) {
      throw Error("inputs '" + paths[0].string() + "' and '" + paths[1].string() +
                  "' have the same format: say which sensor replays which (NAME=PATH)");
    }
    bool used = false;
    for (std::size_t i = 0; i < sensors.size(); ++i) {
      if (named[i] || !takes(sensors[i], format)) continue;
      out[i] = recording_for(sensors[i], paths[0], format);
      used = true;
    }
    if (!used) {
      throw Error("input '" + paths[0].string() + "': no sensor of the configuration reads a " +
                  std::string(enum_name(format)) + " recording");
    }
  }
  return out;
}

}  // namespace livod::daemon::replay
