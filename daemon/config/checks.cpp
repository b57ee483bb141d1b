// Checks that need every sensor at once. Each check skips sensors whose own reading already
// failed in the relevant part, so that one mistake is reported once.

#include <map>
#include <set>
#include <tuple>

#include "daemon/config/readers.hpp"
#include "daemon/config/sensor_models.hpp"
#include "estimator/lidars.hpp"

namespace livod::daemon::config_detail {

namespace {

constexpr std::string_view kInternalImuSuffix = ".imu";

std::string sensor_label(const std::vector<SensorSite>& sites, const LivodConfig& config,
                         std::size_t i) {
  std::string label = sites[i].path;
  if (sites[i].name_ok) label += " '" + config.sensors[i].name + "'";
  return label;
}

std::string line_of(Position at) {
  return at.line > 0 ? " (line " + std::to_string(at.line) + ")" : std::string();
}

void check_unique_names(ProblemList& problems, const LivodConfig& config,
                        const std::vector<SensorSite>& sites) {
  std::map<std::string, std::size_t> first;
  for (std::size_t i = 0; i < sites.size(); ++i) {
    if (!sites[i].name_ok) continue;
    const auto [it, inserted] = first.emplace(config.sensors[i].name, i);
    if (!inserted) {
      problems.error(ProblemKind::duplicate_name, sites[i].path + ".name", sites[i].name_at,
                     "sensor name '" + config.sensors[i].name + "' is already used by " +
                         sites[it->second].path + line_of(sites[it->second].name_at));
    }
  }
}

// Resolves body_frame to a sensor index; reports what is wrong with it.
void resolve_body_frame(ProblemList& problems, LivodConfig& config,
                        const std::vector<SensorSite>& sites, Position at) {
  const std::string& body = config.body_frame;
  std::string name = body;
  bool internal = false;
  if (body.size() > kInternalImuSuffix.size() &&
      body.compare(body.size() - kInternalImuSuffix.size(), kInternalImuSuffix.size(),
                   kInternalImuSuffix) == 0) {
    name = body.substr(0, body.size() - kInternalImuSuffix.size());
    internal = true;
  }
  std::vector<std::string> candidates;
  int index = -1;
  for (std::size_t i = 0; i < sites.size(); ++i) {
    if (!sites[i].name_ok || !sites[i].driver_known) continue;
    const SensorConfig& s = config.sensors[i];
    if (sensor_kind(s.driver) == SensorKind::imu) candidates.push_back(s.name);
    if (s.imu.enabled) candidates.push_back(s.name + std::string(kInternalImuSuffix));
    if (s.name == name && index < 0) index = static_cast<int>(i);
  }
  if (index < 0) {
    // The sensor may exist with a broken driver or name: that problem is reported already.
    for (std::size_t i = 0; i < sites.size(); ++i) {
      if (sites[i].name_ok && config.sensors[i].name == name) return;
    }
    problems.error(ProblemKind::invalid_value, "body_frame", at,
                   "no IMU named '" + body + "'" + did_you_mean(body, candidates) +
                       (candidates.empty() ? "; the configuration has no IMU"
                                           : "; IMUs: " + join(candidates)));
    return;
  }
  const SensorConfig& s = config.sensors[static_cast<std::size_t>(index)];
  const std::string label = sensor_label(sites, config, static_cast<std::size_t>(index));
  if (internal) {
    if (!model_has_internal_imu(s.driver, s.model)) {
      problems.error(ProblemKind::inconsistent, "body_frame", at,
                     label + " has no internal IMU" +
                         (candidates.empty() ? std::string() : "; IMUs: " + join(candidates)));
      return;
    }
    if (!s.imu.enabled) {
      problems.error(ProblemKind::inconsistent, "body_frame", at,
                     "the internal IMU of " + label + " is disabled (imu.enabled: false)");
      return;
    }
  } else if (sensor_kind(s.driver) != SensorKind::imu) {
    std::string hint = candidates.empty() ? std::string() : "; IMUs: " + join(candidates);
    if (s.imu.enabled) hint = "; its internal IMU is '" + s.name + ".imu'";
    problems.error(
        ProblemKind::inconsistent, "body_frame", at,
        label + " is a " + std::string(enum_name(sensor_kind(s.driver))) + ", not an IMU" + hint);
    return;
  }
  if (!s.enabled) {
    problems.error(ProblemKind::inconsistent, "body_frame", at,
                   "the body IMU " + label + " is disabled");
    return;
  }
  config.body_sensor_index = index;
  config.body_is_internal_imu = internal;
}

bool is_identity(const Eigen::Isometry3d& T) {
  constexpr double kTolerance = 1e-9;
  return T.isApprox(Eigen::Isometry3d::Identity(), kTolerance) &&
         T.translation().norm() < kTolerance;
}

// Every sensor except the body IMU needs T_body_sensor; relative_to chains are followed.
void check_extrinsics(ProblemList& problems, LivodConfig& config,
                      const std::vector<SensorSite>& sites) {
  const std::size_t n = config.sensors.size();
  const int body = config.body_sensor_index;
  const bool body_known = body >= 0;
  const std::string body_sensor_name = config.body_frame.substr(0, config.body_frame.find('.'));
  auto is_body_imu = [&](std::size_t i) {
    return body_known && !config.body_is_internal_imu && static_cast<int>(i) == body;
  };

  for (std::size_t i = 0; i < n; ++i) {
    if (!sites[i].readable) continue;
    const SensorConfig& s = config.sensors[i];
    if (is_body_imu(i)) {
      if (s.extrinsic &&
          (!s.extrinsic->relative_to.empty() || !is_identity(s.extrinsic->T_reference_sensor))) {
        problems.error(ProblemKind::inconsistent, sites[i].path + ".extrinsic",
                       sites[i].extrinsic_at,
                       "the body IMU defines the body frame: its extrinsic must be identity "
                       "(leave it out)");
      }
      continue;
    }
    if (sites[i].has_extrinsic_key || !s.enabled) continue;
    // Without a resolved body frame any IMU may be the one meant as body: none is blamed.
    if (!body_known && sites[i].driver_known && sensor_kind(s.driver) == SensorKind::imu) {
      continue;
    }
    if (!body_known && !sites[i].driver_known) continue;
    const std::string body_text =
        body_known ? "the body IMU '" + config.body_frame + "'" : std::string("the body IMU");
    problems.error(ProblemKind::missing_extrinsic, sites[i].path + ".extrinsic", sites[i].at,
                   sensor_label(sites, config, i) + " needs an extrinsic (T_body_sensor); only " +
                       body_text + " may leave it out");
  }

  enum class State { unresolved, resolving, resolved, failed };
  std::vector<State> state(n, State::unresolved);
  std::vector<Eigen::Isometry3d> T_body(n, Eigen::Isometry3d::Identity());
  std::vector<int> reference(n, -1);  // -1: relative to the body frame
  std::map<std::string, std::size_t> by_name;
  for (std::size_t i = 0; i < n; ++i) {
    if (sites[i].name_ok) by_name.emplace(config.sensors[i].name, i);
  }
  std::vector<std::string> names;
  for (const auto& [name, index] : by_name) names.push_back(name);

  // Finds what sensor i's extrinsic is relative to, or marks it failed (reporting the reason).
  auto find_reference = [&](std::size_t i) -> bool {
    const SensorConfig& s = config.sensors[i];
    if (is_body_imu(i)) {
      state[i] = State::resolved;
      return false;
    }
    if (!s.extrinsic || !sites[i].extrinsic_ok) {
      state[i] = State::failed;
      return false;
    }
    const std::string& ref = s.extrinsic->relative_to;
    const std::string path = sites[i].path + ".extrinsic.relative_to";
    if (ref.empty() || ref == "body" || ref == config.body_frame ||
        (body_known && !config.body_is_internal_imu &&
         ref == config.sensors[static_cast<std::size_t>(body)].name)) {
      T_body[i] = s.extrinsic->T_reference_sensor;
      state[i] = State::resolved;
      return false;
    }
    const auto it = by_name.find(ref);
    if (it == by_name.end()) {
      problems.error(ProblemKind::invalid_value, path, sites[i].relative_to_at,
                     "no sensor named '" + ref + "'" + did_you_mean(ref, names));
      state[i] = State::failed;
      return false;
    }
    if (it->second == i) {
      problems.error(ProblemKind::inconsistent, path, sites[i].relative_to_at,
                     "a sensor cannot be relative to itself");
      state[i] = State::failed;
      return false;
    }
    reference[i] = static_cast<int>(it->second);
    return true;
  };

  for (std::size_t start = 0; start < n; ++start) {
    if (state[start] != State::unresolved) continue;
    // Walk the relative_to chain iteratively (chains may be long in odd files; no recursion).
    std::vector<std::size_t> chain;
    std::size_t cur = start;
    while (state[cur] == State::unresolved && find_reference(cur)) {
      state[cur] = State::resolving;
      chain.push_back(cur);
      const auto next = static_cast<std::size_t>(reference[cur]);
      if (state[next] == State::resolving) {
        problems.error(
            ProblemKind::inconsistent, sites[cur].path + ".extrinsic.relative_to",
            sites[cur].relative_to_at,
            "relative_to chains form a loop through " + sensor_label(sites, config, next));
        state[next] = State::failed;
        break;
      }
      cur = next;
    }
    for (auto it = chain.rbegin(); it != chain.rend(); ++it) {
      const std::size_t i = *it;
      const auto ref = static_cast<std::size_t>(reference[i]);
      if (state[ref] == State::resolved) {
        T_body[i] = T_body[ref] * config.sensors[i].extrinsic->T_reference_sensor;
        state[i] = State::resolved;
      } else {
        state[i] = State::failed;
      }
    }
  }
  for (std::size_t i = 0; i < n; ++i) {
    if (state[i] == State::resolved) config.sensors[i].T_body_sensor = T_body[i];
  }
}

void check_lidar_present(ProblemList& problems, const LivodConfig& config,
                         const std::vector<SensorSite>& sites, Position sensors_at) {
  if (sites.empty()) return;
  for (std::size_t i = 0; i < sites.size(); ++i) {
    if (!sites[i].driver_known) return;  // might have been the LiDAR
    const SensorConfig& s = config.sensors[i];
    if (s.enabled && sensor_kind(s.driver) == SensorKind::lidar) return;
  }
  problems.error(ProblemKind::inconsistent, "sensors", sensors_at,
                 "no enabled LiDAR: livod's estimator needs at least one");
}

void check_live_replay_mix(ProblemList& problems, const LivodConfig& config,
                           const std::vector<SensorSite>& sites) {
  int first = -1;
  for (std::size_t i = 0; i < sites.size(); ++i) {
    if (!sites[i].source_ok || !config.sensors[i].enabled) continue;
    if (first < 0) {
      first = static_cast<int>(i);
      continue;
    }
    const auto f = static_cast<std::size_t>(first);
    if (sites[i].is_replay != sites[f].is_replay) {
      problems.error(ProblemKind::inconsistent, sites[i].path + ".source", sites[i].at,
                     sensor_label(sites, config, i) + " is " +
                         (sites[i].is_replay ? "replayed" : "live") + " while " +
                         sensor_label(sites, config, f) + " is " +
                         (sites[f].is_replay ? "replayed" : "live") +
                         ": a run is either live or a replay (disable one or the other)");
      return;
    }
  }
}

std::uint16_t port_value(const UdpPorts& ports, std::size_t index) {
  switch (index) {
    case 0:
      return ports.lidar;
    case 1:
      return ports.imu;
    case 2:
      return ports.position;
    case 3:
      return ports.command;
    default:
      return ports.push;
  }
}

// Each stream needs its own local (address, port): one capture thread owns one socket. A socket
// bound to 0.0.0.0 conflicts with every address on that port.
void check_ports(ProblemList& problems, const LivodConfig& config,
                 const std::vector<SensorSite>& sites) {
  struct Stream {
    std::size_t sensor;
    std::size_t port_index;
  };
  const std::string wildcard = "0.0.0.0";
  // port -> (bind address -> first stream), and port -> first stream on any address
  std::map<std::uint16_t, std::map<std::string, Stream>> by_address;
  std::map<std::uint16_t, Stream> first_on_port;

  for (std::size_t i = 0; i < sites.size(); ++i) {
    const SensorConfig& s = config.sensors[i];
    const auto* udp = std::get_if<UdpSourceConfig>(&s.source);
    if (!sites[i].source_ok || !s.enabled || udp == nullptr) continue;
    const auto names = port_names(s.driver);
    std::map<std::uint16_t, std::size_t> own;  // this sensor's ports
    for (std::size_t p = 0; p < kPortNames.size(); ++p) {
      if (std::find(names.begin(), names.end(), kPortNames[p]) == names.end()) continue;
      if (p == 1 && !s.imu.enabled) continue;  // the internal IMU's port is not bound
      if (sites[i].port_invalid[p]) continue;
      const std::uint16_t port = port_value(udp->ports, p);
      if (port == 0) continue;
      const std::string path = sites[i].path + ".source.udp.ports." + kPortNames[p];
      const std::string port_text =
          "port " + std::to_string(port) + (sites[i].port_given[p] ? std::string() : " (default)");
      // Within one sensor, points and IMU may share a port (Ouster, Livox tell them apart).
      if (const auto it = own.find(port); it != own.end()) {
        const bool lidar_imu = (it->second == 0 && p == 1) || (it->second == 1 && p == 0);
        if (!lidar_imu) {
          problems.error(ProblemKind::duplicate_port, path, sites[i].port_at[p],
                         port_text + " is also this sensor's " + kPortNames[it->second] + " port");
        }
        continue;
      }
      own.emplace(port, p);

      const Stream* conflict = nullptr;
      auto& on_port = by_address[port];
      if (udp->bind_address == wildcard) {
        if (const auto it = first_on_port.find(port); it != first_on_port.end()) {
          conflict = &it->second;
        }
      } else if (const auto w = on_port.find(wildcard); w != on_port.end()) {
        conflict = &w->second;
      } else if (const auto a = on_port.find(udp->bind_address); a != on_port.end()) {
        conflict = &a->second;
      }
      if (conflict != nullptr) {
        const std::size_t other = conflict->sensor;
        problems.error(ProblemKind::duplicate_port, path, sites[i].port_at[p],
                       port_text + " on " + udp->bind_address + " is already used by " +
                           sensor_label(sites, config, other) + " for its " +
                           kPortNames[conflict->port_index] + " stream" +
                           line_of(sites[other].port_at[conflict->port_index]) +
                           "; give each stream its own port");
        continue;
      }
      on_port.emplace(udp->bind_address, Stream{i, p});
      first_on_port.emplace(port, Stream{i, p});
    }
  }
}

void check_camera_sizes(ProblemList& problems, const LivodConfig& config,
                        const std::vector<SensorSite>& sites) {
  const auto& vio = config.estimator.vio;
  if (!vio.enabled) return;
  // The photometric update needs a patch (plus one pixel for gradients) at the coarsest level.
  const int border = (vio.patch_size / 2 + 1) * (1 << (vio.pyramid_levels - 1));
  for (std::size_t i = 0; i < sites.size(); ++i) {
    const SensorConfig& s = config.sensors[i];
    if (!sites[i].camera_ok || !s.enabled || !sites[i].driver_known ||
        sensor_kind(s.driver) != SensorKind::camera) {
      continue;
    }
    const int width = static_cast<int>(s.camera.width * s.camera.scale);
    const int height = static_cast<int>(s.camera.height * s.camera.scale);
    if (width <= 2 * border || height <= 2 * border) {
      problems.error(ProblemKind::inconsistent, sites[i].path + ".camera", sites[i].camera_at,
                     "the scaled image (" + std::to_string(width) + "x" + std::to_string(height) +
                         " px) is not larger than twice the " + std::to_string(border) +
                         " px border that estimator.vio.patch_size and pyramid_levels need");
    }
  }
}

// What livod cannot run yet is an error here, at check-config time, never a silent no-op at run
// time: a configured sensor the estimator would not use, or a driver that is not built.
void check_implemented(ProblemList& problems, const LivodConfig& config,
                       const std::vector<SensorSite>& sites) {
  int first_lidar = -1;
  std::size_t enabled_lidars = 0;
  std::size_t lidars_building_map = 0;
  int first_camera = -1;
  // The visual update runs when VIO is enabled and a camera is.
  bool visual_update = false;
  for (std::size_t i = 0; i < sites.size(); ++i) {
    const SensorConfig& s = config.sensors[i];
    if (sites[i].driver_known && s.enabled && sensor_kind(s.driver) == SensorKind::camera) {
      visual_update = config.estimator.vio.enabled;
    }
  }
  for (std::size_t i = 0; i < sites.size(); ++i) {
    const SensorConfig& s = config.sensors[i];
    if (!sites[i].driver_known || !s.enabled) continue;
    const std::string where = sensor_label(sites, config, i);
    switch (sensor_kind(s.driver)) {
      case SensorKind::camera:
        // The visual update takes one camera: live (source.device) or replayed (source.replay:
        // image folders, bag image topics).
        if (!config.estimator.vio.enabled) {
          problems.warning(ProblemKind::inconsistent, sites[i].path + ".enabled", sites[i].at,
                           where + " is not used: estimator.vio.enabled is false (LiDAR-inertial " +
                               "odometry only)");
        } else if (first_camera >= 0) {
          problems.error(ProblemKind::not_implemented, sites[i].path + ".enabled", sites[i].at,
                         where + " and " +
                             sensor_label(sites, config, static_cast<std::size_t>(first_camera)) +
                             " are both enabled, but the visual update uses one camera: disable "
                             "one");
        } else {
          first_camera = static_cast<int>(i);
        }
        break;
      case SensorKind::lidar: {
        // Every enabled LiDAR feeds the estimator (docs/estimator.md "Several LiDARs"), up to
        // estimator::kMaxLidars, and LiDAR-inertial only: the visual update takes one LiDAR's scan.
        ++enabled_lidars;
        if (s.lio.build_map) ++lidars_building_map;
        // "<this LiDAR> and <the first> are both enabled", for what takes one LiDAR.
        const auto both_lidars = [&] {
          return where + " and " +
                 sensor_label(sites, config, static_cast<std::size_t>(first_lidar)) +
                 " are both enabled";
        };
        if (first_lidar < 0) {
          first_lidar = static_cast<int>(i);
        } else if (enabled_lidars > estimator::kMaxLidars) {
          problems.error(ProblemKind::not_implemented, sites[i].path + ".enabled", sites[i].at,
                         where + " is LiDAR number " + std::to_string(enabled_lidars) +
                             ": the estimator fuses at most " +
                             std::to_string(estimator::kMaxLidars) + " LiDARs: disable one");
        } else if (visual_update) {
          problems.error(ProblemKind::not_implemented, sites[i].path + ".enabled", sites[i].at,
                         both_lidars() + " with a camera and estimator.vio.enabled: the " +
                             "visual update runs with one LiDAR only (disable one LiDAR, or set " +
                             "estimator.vio.enabled: false to fuse both LiDAR-inertially)");
        }
        break;
      }
      case SensorKind::imu:
        if (sites[i].name_ok && config.body_sensor_index >= 0 &&
            static_cast<std::size_t>(config.body_sensor_index) != i) {
          problems.error(ProblemKind::not_implemented, sites[i].path + ".enabled", sites[i].at,
                         where + " is not the body IMU (body_frame: " + config.body_frame +
                             ") and the estimator takes one IMU: disable it or make it the body");
        }
        break;
    }
    // Live devices (cameras, CAN and serial IMUs) run in `livod run` (daemon/runtime/live_*);
    // their recordings (candump logs, serial captures, image folders) replay.
  }
  if (enabled_lidars > 0 && lidars_building_map == 0) {
    // Some LiDAR must insert its points: with none, the map stays empty and nothing matches.
    for (std::size_t i = 0; i < sites.size(); ++i) {
      const SensorConfig& s = config.sensors[i];
      if (!sites[i].driver_known || !s.enabled || sensor_kind(s.driver) != SensorKind::lidar) {
        continue;
      }
      problems.error(ProblemKind::inconsistent, sites[i].path + ".lio.build_map", sites[i].at,
                     sensor_label(sites, config, i) +
                         " has lio.build_map: false and no other enabled LiDAR builds the map: "
                         "at least one LiDAR must (its points are what the others match)");
    }
  }
}

}  // namespace

void check_sensors(ProblemList& problems, LivodConfig& config, const std::vector<SensorSite>& sites,
                   Position sensors_at, Position body_frame_at) {
  check_unique_names(problems, config, sites);
  if (!config.body_frame.empty()) resolve_body_frame(problems, config, sites, body_frame_at);
  check_extrinsics(problems, config, sites);
  check_lidar_present(problems, config, sites, sensors_at);
  check_live_replay_mix(problems, config, sites);
  check_ports(problems, config, sites);
  check_camera_sizes(problems, config, sites);
  check_implemented(problems, config, sites);
}

}  // namespace livod::daemon::config_detail
