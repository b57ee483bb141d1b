#include "daemon/preflight.hpp"

#include <exception>
#include <optional>
#include <string>

#include "daemon/config/sensor_models.hpp"
#include "daemon/replay/decoder_factory.hpp"
#include "daemon/replay/input_assignment.hpp"
#include "daemon/replay/sources.hpp"

namespace livod::daemon {
namespace {

// The sensors a replay feeds the estimator: the body IMU and the body's own LiDAR, else the first
// enabled LiDAR (replay_engine.hpp).
bool replayed(const LivodConfig& config, std::size_t index) {
  if (config.body_sensor_index >= 0 &&
      index == static_cast<std::size_t>(config.body_sensor_index)) {
    return true;
  }
  if (config.body_is_internal_imu) return false;
  for (std::size_t i = 0; i < config.sensors.size(); ++i) {
    const auto& s = config.sensors[i];
    if (s.enabled && sensor_kind(s.driver) == SensorKind::lidar) return i == index;
  }
  return false;
}

}  // namespace

std::vector<ConfigProblem> check_config_files(const LivodConfig& config, bool open_recordings) {
  std::vector<ConfigProblem> problems;
  const auto fail = [&](const SensorConfig& sensor, std::size_t i, const std::string& key,
                        const std::string& message) {
    ConfigProblem p;
    p.severity = Severity::error;
    p.kind = ProblemKind::inconsistent;
    p.path = "sensors[" + std::to_string(i) + "]" + (key.empty() ? "" : "." + key);
    p.line = sensor.line;
    p.column = sensor.line > 0 ? 1 : 0;
    p.message = message;
    problems.push_back(std::move(p));
  };
  std::vector<std::optional<replay::SensorRecording>> recordings;
  if (open_recordings) {
    try {
      recordings = replay::assign_recordings(config, {});
    } catch (const std::exception& e) {
      ConfigProblem p;
      p.kind = ProblemKind::inconsistent;
      p.message = e.what();
      problems.push_back(std::move(p));
      open_recordings = false;
    }
  }
  for (std::size_t i = 0; i < config.sensors.size(); ++i) {
    const SensorConfig& sensor = config.sensors[i];
    if (!sensor.enabled) continue;
    const bool packet_lidar = is_packet_lidar(sensor.driver);
    const std::string file_key = sensor.driver == Driver::ouster     ? "metadata"
                                 : sensor.driver == Driver::velodyne ? "calibration"
                                                                     : "";
    try {
      if (open_recordings && recordings[i] && replayed(config, i)) {
        // Exactly what the replay does: opens the recording and builds its decoder.
        (void)replay::make_source(sensor, recordings[i]->replay, recordings[i]->ports);
      } else if (packet_lidar && !(sensor.driver == Driver::ouster && sensor.metadata.empty())) {
        (void)replay::make_lidar_decoder(sensor);
      }
    } catch (const std::exception& e) {
      fail(sensor, i, file_key, e.what());
    }
  }
  return problems;
}

ConfigResult load_checked_config(const std::filesystem::path& path, bool open_recordings) {
  ConfigResult loaded = load_config(path);
  if (loaded.ok()) {
    for (auto& p : check_config_files(loaded.config, open_recordings)) {
      loaded.problems.push_back(std::move(p));
    }
  }
  return loaded;
}

}  // namespace livod::daemon
