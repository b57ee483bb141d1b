#pragma once
// Internal to livod_daemon_config: the section readers behind load_config() and the checks that
// span several sensors. Each reader declares the keys of its section, converts and range-checks
// the values, and reports problems; none of them throws on bad input.

#include <array>
#include <filesystem>
#include <set>
#include <string>
#include <vector>

#include "daemon/config/config.hpp"
#include "daemon/config/yaml_reader.hpp"

namespace livod::daemon::config_detail {

struct ReadContext {
  std::filesystem::path base_dir;  // relative paths are resolved against it
};

// Where the parts of one sensor are in the file, and which parts were read without problems;
// the cross-sensor checks use it to point at the right line and to avoid cascades of problems
// that all stem from one mistake.
struct SensorSite {
  std::string path;  // "sensors[2]"
  Position at;
  bool readable = false;  // a mapping
  bool name_ok = false;
  Position name_at;
  bool driver_known = false;
  bool source_ok = false;  // exactly one valid source
  bool is_replay = false;
  bool has_extrinsic_key = false;
  bool extrinsic_ok = false;
  Position extrinsic_at;
  Position relative_to_at;
  bool camera_ok = false;
  Position camera_at;
  std::string bind_address_path;
  // Positions of source.udp.ports.<name> (or of the udp section when defaulted), by stream.
  std::array<Position, 5> port_at{};
  std::array<bool, 5> port_given{};
  std::array<bool, 5> port_invalid{};  // reported already; left out of the conflict check
};

// Stream names in UdpPorts order, the index used by SensorSite::port_at.
inline constexpr std::array<const char*, 5> kPortNames = {"lidar", "imu", "position", "command",
                                                          "push"};

void read_sensor(ProblemList& problems, const Value& item, const ReadContext& context,
                 SensorConfig& sensor, SensorSite& site);
void read_extrinsic(MapReader& reader, SensorConfig& sensor, SensorSite& site);
void read_camera(MapReader& reader, Driver driver, CameraConfig& camera, bool& ok);
void read_can(MapReader& reader, CanConfig& can);
// `given` collects the keys the file set that the model defaults would otherwise choose.
void read_estimator(MapReader& reader, estimator::EstimatorParams& params,
                    std::set<std::string>& given);
void read_outputs(MapReader& reader, const ReadContext& context, OutputsConfig& outputs);

// A path from the file, resolved against the config folder.
std::filesystem::path resolve_path(const ReadContext& context, const std::string& text);
bool is_ipv4(const std::string& text);
bool is_host_name(const std::string& text);

// Checks that need all sensors: unique names, body frame, extrinsics (and their relative_to
// chains), at least one LiDAR, live/replay mix, UDP port conflicts, camera size vs VIO border.
void check_sensors(ProblemList& problems, LivodConfig& config, const std::vector<SensorSite>& sites,
                   Position sensors_at, Position body_frame_at);

}  // namespace livod::daemon::config_detail
