#include "daemon/config/summary.hpp"

#include <algorithm>
#include <cmath>
#include <iomanip>
#include <sstream>

#include "daemon/config/estimator_defaults.hpp"
#include "daemon/config/rotation.hpp"

namespace livod::daemon {

namespace {

std::string describe_source(const SensorConfig& s) {
  std::ostringstream out;
  if (const auto* udp = std::get_if<UdpSourceConfig>(&s.source)) {
    out << "udp " << udp->bind_address;
    const UdpPorts& p = udp->ports;
    const std::pair<const char*, std::uint16_t> ports[] = {{"lidar", p.lidar},
                                                           {"imu", p.imu},
                                                           {"position", p.position},
                                                           {"command", p.command},
                                                           {"push", p.push}};
    for (const auto& [name, port] : ports) {
      if (port != 0) out << ' ' << name << ':' << port;
    }
    if (!udp->sensor_address.empty()) out << " from " << udp->sensor_address;
    if (!udp->multicast_group.empty()) out << " group " << udp->multicast_group;
  } else if (const auto* replay = std::get_if<ReplaySourceConfig>(&s.source)) {
    out << "replay " << enum_name(replay->format) << ' ' << replay->file.string();
    if (!replay->topic.empty()) out << " topic " << replay->topic;
  } else if (const auto* device = std::get_if<DeviceSourceConfig>(&s.source)) {
    out << "device ";
    if (!device->path.empty()) out << device->path;
    if (!device->interface.empty()) out << device->interface;
    if (s.driver == Driver::aravis) {
      out << (device->camera_id.empty() ? "first camera found" : device->camera_id);
    }
  }
  return out.str();
}

std::string describe_pose(const Eigen::Isometry3d& T) {
  // Values that print as zero are printed as zero, not as "-0.000".
  const auto tidy = [](Eigen::Vector3d v, double resolution) {
    for (int i = 0; i < 3; ++i) {
      if (std::abs(v[i]) < resolution) v[i] = 0.0;
    }
    return v;
  };
  const Eigen::Vector3d t = tidy(T.translation(), 5e-4);
  const Eigen::Vector3d rpy = tidy(rpy_deg_from_rotation(T.linear()), 5e-3);
  std::ostringstream out;
  out << std::fixed << std::setprecision(3) << "t [" << t.x() << ", " << t.y() << ", " << t.z()
      << "] m, rpy [" << std::setprecision(2) << rpy.x() << ", " << rpy.y() << ", " << rpy.z()
      << "] deg";
  return out.str();
}

std::string file_or_none(const std::filesystem::path& p) {
  return p.empty() ? std::string("none") : p.string();
}

}  // namespace

std::string summarize_config(const LivodConfig& config) {
  std::ostringstream out;
  out << "body frame: " << config.body_frame << '\n';
  std::size_t enabled = 0;
  for (const auto& s : config.sensors) enabled += s.enabled ? 1 : 0;
  out << "sensors: " << config.sensors.size() << " (" << enabled << " enabled)\n";
  std::size_t enabled_lidars = 0;
  for (const auto& s : config.sensors) {
    enabled_lidars += s.enabled && sensor_kind(s.driver) == SensorKind::lidar ? 1 : 0;
  }
  for (std::size_t i = 0; i < config.sensors.size(); ++i) {
    const SensorConfig& s = config.sensors[i];
    out << "  " << s.name << ": " << enum_name(s.driver);
    if (!s.model.empty()) out << ' ' << s.model;
    if (!s.enabled) out << " (disabled)";
    out << ", " << describe_source(s);
    if (s.imu.enabled) {
      // The HDL-32E's IMU shares the position packets (and port) with the GPS time.
      out << (s.driver == Driver::velodyne ? ", internal IMU (in the position packets)"
                                           : ", internal IMU");
    }
    if (sensor_kind(s.driver) == SensorKind::camera) {
      out << ", " << enum_name(s.camera.model) << ' ' << s.camera.width << 'x' << s.camera.height;
      if (s.camera.scale != 1.0) out << " x" << s.camera.scale;
    }
    if (config.body_sensor_index == static_cast<int>(i) && !config.body_is_internal_imu) {
      out << ", body frame";
    } else {
      out << ", T_body_sensor " << describe_pose(s.T_body_sensor);
    }
    if (s.time_offset_s != 0.0) out << ", time offset " << s.time_offset_s << " s";
    const bool own_lio = s.lio.dept_err || s.lio.beam_err_deg || s.lio.point_filter_num ||
                         s.lio.sigma_num || !s.lio.build_map;
    if (sensor_kind(s.driver) == SensorKind::lidar && (enabled_lidars > 1 || own_lio)) {
      // Each LiDAR's point model, and where it comes from: its own lio:, its model's defaults or
      // estimator.lio.
      const auto& lio = config.estimator.lio;
      const auto from = [&](const char* key, bool own) -> std::string {
        if (s.lio_from_model.contains(key)) return " (" + s.model + " default)";
        return own ? "" : " (estimator.lio)";
      };
      out << ", point noise: range " << s.lio.dept_err.value_or(lio.dept_err) << " m"
          << from("dept_err", s.lio.dept_err.has_value()) << ", bearing "
          << s.lio.beam_err_deg.value_or(lio.beam_err_deg) << " deg"
          << from("beam_err_deg", s.lio.beam_err_deg.has_value()) << ", one point in "
          << s.lio.point_filter_num.value_or(lio.point_filter_num)
          << from("point_filter_num", s.lio.point_filter_num.has_value())
          << (s.lio.build_map ? ", builds the map" : ", matched only (does not build the map)")
          << (s.lio_from_model.contains("build_map")
                  ? " (" + s.model + " default: sparse rings beside a denser LiDAR)"
                  : "");
      if (s.lio.sigma_num) {
        out << ", gate " << *s.lio.sigma_num << " sigma"
            << (s.lio_from_model.contains("sigma_num") ? " (matched-only default)" : "");
      }
    }
    out << '\n';
  }
  if (!config.estimator_choices.empty()) {
    const int lidar = estimator_lidar_index(config);
    const SensorConfig& s = config.sensors[static_cast<std::size_t>(lidar)];
    out << "estimator on " << s.name << (s.model.empty() ? "" : " (" + s.model + ")")
        << ", effective values:\n";
    std::size_t width = 0;
    for (const auto& c : config.estimator_choices) {
      width = std::max(width, c.key.size() + 1 + c.value.size());
    }
    for (const auto& c : config.estimator_choices) {
      const std::string kv = c.key + ' ' + c.value;
      out << "  " << kv << std::string(width - kv.size() + 2, ' ') << c.reason << '\n';
    }
  }
  const auto& lcm = config.outputs.lcm;
  out << "outputs: lcm ";
  if (lcm.enabled) {
    out << lcm.url;
    if (!lcm.channel_suffix.empty()) out << " (channel suffix " << lcm.channel_suffix << ')';
    out << (lcm.publish_imu_rate ? ", IMU-rate pose" : "") << (lcm.publish_cloud ? ", cloud" : "")
        << (lcm.publish_bot_core_pose
                ? ", bot_core pose on " + lcm.channel(lcm.channels.bot_core_pose)
                : std::string());
  } else {
    out << "off";
  }
  out << "; trajectory " << file_or_none(config.outputs.trajectory) << "; map "
      << file_or_none(config.outputs.map_pcd) << "; timing "
      << file_or_none(config.outputs.timing_report) << '\n';
  const auto& saves = config.outputs.map_saves;
  out << "map saves (SIGUSR1, livod save-map): ";
  if (saves.enabled) {
    out << (saves.directory.empty() ? std::string("$STATE_DIRECTORY/maps, else ./maps")
                                    : saves.directory.string())
        << (saves.overwrite ? ", each replacing map.pcd" : ", numbered files")
        << (saves.at_stop ? ", and at stop" : "") << '\n';
  } else {
    out << "off\n";
  }
  return out.str();
}

}  // namespace livod::daemon
