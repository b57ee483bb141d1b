// Custom scenarios from YAML. Every problem is collected and reported together.
//
//   base: room_handheld_avia      # optional: start from a named scenario, override below
//   name: my_run
//   description: ...
//   world: room | corridor | corridor_side_rooms | street
//   street_length_m: 420
//   duration_s: 30
//   trajectory:                   # each of x y z roll pitch yaw: {c0, c1, terms: [[a, w,
//   phase]...]}
//     x: {c0: 0, c1: 1.0, terms: [[0.2, 0.5, 0.0]]}
//     yaw_follows_heading: true
//     static_duration_s: 2
//     ramp_duration_s: 2
//   lidars:                       # replaces the base's list when present
//     - {model: AVIA, name: avia, translation: [0.04, 0.02, -0.03], rpy_deg: [0, 0, 0],
//        clock: {offset_s: 5, skew_ppm: 20, jitter_s: 0, reset_at_s: -1},
//        link: {delay_floor_s: 8e-5, delay_mean_s: 4e-5, loss_probability: 0.0},
//        range: {sigma_m: 0.02, min_m: 0.2, max_m: 200, dropout: 0.002, detection_limited: true,
//                sigma_at_limit_m: 0.08, intensity_bias_m: 0.0, divergence_deg: [0.03, 0.28],
//                pulse_length_m: 0.75},
//        scan_rate_hz: 10, imu: true}
//   scene: {pedestrians: 2, cars: 1, foliage: true}   # per 100 m of street / per room
//   body_imu: avia
//   cameras: []                   # clears the base's cameras (only clearing is supported)
//   can_imu:                      # adds or changes the CAN IMU
//     {name: can_imu, format: sbg | bosch_mm7, rate_hz: 100, translation: [0, 0, 0],
//      rpy_deg: [0, 0, 0]}
//   serial_imu:                   # adds an IMU on a serial line (Xsens MTi or VectorNav VN-100)
//     {name: xsens, protocol: xsens_mtdata2 | vectornav_binary, rate_hz: 400, baud_rate: 921600,
//     max_read_bytes: 64, read_latency_s: 1e-3,
//      corrupt_probability: 0.01, noise_probability: 0.01, clock: {offset_s: 3, skew_ppm: -30}}

#include <yaml-cpp/yaml.h>

#include <cmath>
#include <sstream>

#include "core/error.hpp"
#include "tools/sim/scenario.hpp"

namespace livod::sim {
namespace {

class Problems {
 public:
  void add(const YAML::Node& node, const std::string& path, const std::string& message) {
    std::ostringstream os;
    if (node.IsDefined() && node.Mark().line >= 0) os << "line " << node.Mark().line + 1 << ": ";
    os << path << ": " << message;
    list_.push_back(os.str());
  }
  [[nodiscard]] bool empty() const { return list_.empty(); }
  [[nodiscard]] std::string text() const {
    std::string s;
    for (const auto& p : list_) s += "\n  " + p;
    return s;
  }

 private:
  std::vector<std::string> list_;
};

template <class T>
void read(const YAML::Node& map, const char* key, T& out, const std::string& path, Problems& p) {
  const YAML::Node n = map[key];
  if (!n) return;
  try {
    out = n.as<T>();
  } catch (const YAML::Exception&) {
    p.add(n, path + "." + key, "wrong type");
  }
}

void check_keys(const YAML::Node& map, std::initializer_list<const char*> allowed,
                const std::string& path, Problems& p) {
  if (!map.IsMap()) {
    p.add(map, path, "expected a mapping");
    return;
  }
  for (const auto& kv : map) {
    const auto key = kv.first.as<std::string>();
    bool ok = false;
    for (const char* a : allowed) ok = ok || key == a;
    if (!ok) p.add(kv.first, path + "." + key, "unknown key");
  }
}

Eigen::Vector3d vec3(const YAML::Node& n, const std::string& path, Problems& p) {
  try {
    const auto v = n.as<std::vector<double>>();
    if (v.size() == 3) return {v[0], v[1], v[2]};
  } catch (const YAML::Exception&) {
  }
  p.add(n, path, "expected a list of 3 numbers");
  return Eigen::Vector3d::Zero();
}

// translation / rpy_deg (ZYX, degrees) of a mount, when given.
void read_pose(const YAML::Node& n, const std::string& path, Eigen::Isometry3d& T, Problems& p) {
  if (n["translation"]) T.translation() = vec3(n["translation"], path + ".translation", p);
  if (n["rpy_deg"]) {
    const Eigen::Vector3d r = vec3(n["rpy_deg"], path + ".rpy_deg", p) * (M_PI / 180.0);
    T.linear() = (Eigen::AngleAxisd(r.z(), Eigen::Vector3d::UnitZ()) *
                  Eigen::AngleAxisd(r.y(), Eigen::Vector3d::UnitY()) *
                  Eigen::AngleAxisd(r.x(), Eigen::Vector3d::UnitX()))
                     .toRotationMatrix();
  }
}

void read_function(const YAML::Node& n, SmoothFunction& f, const std::string& path, Problems& p) {
  if (!n) return;
  check_keys(n, {"c0", "c1", "terms"}, path, p);
  if (!n.IsMap()) return;
  read(n, "c0", f.c0, path, p);
  read(n, "c1", f.c1, path, p);
  if (const auto terms = n["terms"]) {
    f.terms.clear();
    if (!terms.IsSequence()) {
      p.add(terms, path + ".terms", "expected a list of [amplitude, omega, phase]");
      return;
    }
    for (std::size_t i = 0; i < terms.size(); ++i) {
      try {
        const auto v = terms[i].as<std::vector<double>>();
        if (v.size() != 3) throw YAML::Exception(terms[i].Mark(), "size");
        f.terms.push_back({v[0], v[1], v[2]});
      } catch (const YAML::Exception&) {
        p.add(terms[i], path + ".terms[" + std::to_string(i) + "]",
              "expected [amplitude, omega, phase]");
      }
    }
  }
}

}  // namespace

Scenario load_scenario_yaml(const std::filesystem::path& file) {
  YAML::Node root;
  try {
    root = YAML::LoadFile(file.string());
  } catch (const YAML::Exception& e) {
    throw Error(file.string() + ": " + e.what());
  }
  Problems p;
  Scenario s;
  check_keys(
      root,
      {"base", "name", "description", "world", "street_length_m", "duration_s", "trajectory",
       "lidars", "cameras", "body_imu", "groundtruth_rate_hz", "scene", "can_imu", "serial_imu"},
      "scenario", p);
  if (!root.IsMap()) throw Error(file.string() + ": a scenario file is a YAML mapping");
  if (const auto base = root["base"]) {
    try {
      s = make_scenario(base.as<std::string>());
    } catch (const Error& e) {
      p.add(base, "scenario.base", e.what());
    }
  }
  read(root, "name", s.name, "scenario", p);
  read(root, "description", s.description, "scenario", p);
  read(root, "street_length_m", s.street_length_m, "scenario", p);
  read(root, "duration_s", s.duration_s, "scenario", p);
  read(root, "body_imu", s.body_imu, "scenario", p);
  read(root, "groundtruth_rate_hz", s.groundtruth_rate_hz, "scenario", p);
  if (const auto w = root["world"]) {
    const auto name = w.as<std::string>("");
    if (name == "room")
      s.world = WorldKind::kRoom;
    else if (name == "corridor")
      s.world = WorldKind::kCorridor;
    else if (name == "corridor_side_rooms")
      s.world = WorldKind::kCorridorSideRooms;
    else if (name == "street")
      s.world = WorldKind::kStreet;
    else
      p.add(w, "scenario.world", "expected room, corridor, corridor_side_rooms or street");
  }
  if (const auto sc = root["scene"]) {
    check_keys(sc, {"pedestrians", "cars", "foliage"}, "scenario.scene", p);
    read(sc, "pedestrians", s.scene.pedestrians, "scenario.scene", p);
    read(sc, "cars", s.scene.cars, "scenario.scene", p);
    read(sc, "foliage", s.scene.foliage, "scenario.scene", p);
    if (s.scene.pedestrians < 0.0 || s.scene.pedestrians > 100.0) {
      p.add(sc["pedestrians"], "scenario.scene.pedestrians", "must be within [0, 100]");
    }
    if (s.scene.cars < 0.0 || s.scene.cars > 100.0) {
      p.add(sc["cars"], "scenario.scene.cars", "must be within [0, 100]");
    }
  }
  if (const auto t = root["trajectory"]) {
    check_keys(t,
               {"x", "y", "z", "roll", "pitch", "yaw", "yaw_follows_heading", "static_duration_s",
                "ramp_duration_s"},
               "scenario.trajectory", p);
    auto& tr = s.trajectory;
    read_function(t["x"], tr.x, "scenario.trajectory.x", p);
    read_function(t["y"], tr.y, "scenario.trajectory.y", p);
    read_function(t["z"], tr.z, "scenario.trajectory.z", p);
    read_function(t["roll"], tr.roll, "scenario.trajectory.roll", p);
    read_function(t["pitch"], tr.pitch, "scenario.trajectory.pitch", p);
    read_function(t["yaw"], tr.yaw, "scenario.trajectory.yaw", p);
    read(t, "yaw_follows_heading", tr.yaw_follows_heading, "scenario.trajectory", p);
    read(t, "static_duration_s", tr.static_duration, "scenario.trajectory", p);
    read(t, "ramp_duration_s", tr.ramp_duration, "scenario.trajectory", p);
  }
  if (const auto lidars = root["lidars"]) {
    s.lidars.clear();
    if (!lidars.IsSequence()) p.add(lidars, "scenario.lidars", "expected a list");
    for (std::size_t i = 0; lidars.IsSequence() && i < lidars.size(); ++i) {
      const std::string path = "scenario.lidars[" + std::to_string(i) + "]";
      const auto n = lidars[i];
      check_keys(n,
                 {"model", "name", "translation", "rpy_deg", "clock", "link", "range", "imu",
                  "scan_rate_hz"},
                 path, p);
      if (!n.IsMap()) continue;
      LidarMount m;
      read(n, "model", m.model, path, p);
      // A LiDAR starts from its model's datasheet range model; `range:` overrides parts of it.
      m.range = datasheet_range_model(m.model);
      read(n, "scan_rate_hz", m.scan_rate_hz, path, p);
      if (m.scan_rate_hz != 10.0 && m.scan_rate_hz != 20.0) {
        p.add(n["scan_rate_hz"], path + ".scan_rate_hz", "must be 10 or 20");
      }
      read(n, "name", m.name, path, p);
      read(n, "imu", m.imu, path, p);
      if (m.model.empty()) p.add(n, path + ".model", "required");
      if (m.name.empty()) p.add(n, path + ".name", "required");
      if (n["translation"])
        m.T_body_sensor.translation() = vec3(n["translation"], path + ".translation", p);
      if (n["rpy_deg"]) {
        const Eigen::Vector3d r = vec3(n["rpy_deg"], path + ".rpy_deg", p) * (M_PI / 180.0);
        m.T_body_sensor.linear() = (Eigen::AngleAxisd(r.z(), Eigen::Vector3d::UnitZ()) *
                                    Eigen::AngleAxisd(r.y(), Eigen::Vector3d::UnitY()) *
                                    Eigen::AngleAxisd(r.x(), Eigen::Vector3d::UnitX()))
                                       .toRotationMatrix();
      }
      if (const auto c = n["clock"]) {
        check_keys(c, {"offset_s", "skew_ppm", "jitter_s", "reset_at_s"}, path + ".clock", p);
        read(c, "offset_s", m.clock.offset_s, path + ".clock", p);
        read(c, "skew_ppm", m.clock.skew_ppm, path + ".clock", p);
        read(c, "jitter_s", m.clock.jitter_s, path + ".clock", p);
        read(c, "reset_at_s", m.clock.reset_at_s, path + ".clock", p);
      }
      if (const auto l = n["link"]) {
        check_keys(l,
                   {"delay_floor_s", "delay_mean_s", "spike_probability", "spike_mean_s",
                    "loss_probability"},
                   path + ".link", p);
        read(l, "delay_floor_s", m.link.delay_floor_s, path + ".link", p);
        read(l, "delay_mean_s", m.link.delay_mean_s, path + ".link", p);
        read(l, "spike_probability", m.link.spike_probability, path + ".link", p);
        read(l, "spike_mean_s", m.link.spike_mean_s, path + ".link", p);
        read(l, "loss_probability", m.link.loss_probability, path + ".link", p);
        if (m.link.loss_probability < 0.0 || m.link.loss_probability > 1.0) {
          p.add(l, path + ".link.loss_probability", "must be within [0, 1]");
        }
      }
      if (const auto r = n["range"]) {
        check_keys(r,
                   {"sigma_m", "min_m", "max_m", "dropout", "detection_limited", "sigma_at_limit_m",
                    "intensity_bias_m", "divergence_deg", "pulse_length_m"},
                   path + ".range", p);
        read(r, "sigma_m", m.range.sigma_m, path + ".range", p);
        read(r, "min_m", m.range.min_range_m, path + ".range", p);
        read(r, "max_m", m.range.max_range_m, path + ".range", p);
        read(r, "dropout", m.range.dropout_probability, path + ".range", p);
        read(r, "detection_limited", m.range.detection_limited, path + ".range", p);
        read(r, "sigma_at_limit_m", m.range.sigma_at_limit_m, path + ".range", p);
        read(r, "intensity_bias_m", m.range.intensity_bias_m, path + ".range", p);
        read(r, "pulse_length_m", m.range.pulse_length_m, path + ".range", p);
        if (const auto dv = r["divergence_deg"]) {
          if (!dv.IsSequence() || dv.size() != 2) {
            p.add(dv, path + ".range.divergence_deg",
                  "expected [across the scan, along the column]");
          } else {
            try {
              m.range.divergence_h_rad = dv[0].as<double>() * M_PI / 180.0;
              m.range.divergence_v_rad = dv[1].as<double>() * M_PI / 180.0;
            } catch (const YAML::Exception&) {
              p.add(dv, path + ".range.divergence_deg", "wrong type");
            }
          }
        }
        const RangeModel& rm = m.range;
        if (rm.sigma_m < 0.0 || rm.sigma_at_limit_m < 0.0 || rm.pulse_length_m < 0.0 ||
            rm.divergence_h_rad < 0.0 || rm.divergence_v_rad < 0.0) {
          p.add(r, path + ".range", "noise, divergence and pulse length must not be negative");
        }
        if (rm.dropout_probability < 0.0 || rm.dropout_probability > 1.0) {
          p.add(r["dropout"], path + ".range.dropout", "must be within [0, 1]");
        }
        if (!(rm.max_range_m > rm.min_range_m)) {
          p.add(r, path + ".range", "max_m must exceed min_m");
        }
      }
      s.lidars.push_back(m);
    }
  }
  if (const auto cams = root["cameras"]) {
    if (!cams.IsSequence() || cams.size() != 0) {
      p.add(cams, "scenario.cameras", "only an empty list (no cameras) is supported");
    } else {
      s.cameras.clear();
    }
  }
  if (const auto c = root["can_imu"]) {
    const std::string path = "scenario.can_imu";
    check_keys(c, {"name", "format", "rate_hz", "translation", "rpy_deg"}, path, p);
    CanImuMount m = s.can_imu.value_or(CanImuMount{});
    read(c, "name", m.name, path, p);
    read(c, "rate_hz", m.noise.rate_hz, path, p);
    std::string format = m.format == CanImuFormat::kSbg ? "sbg" : "bosch_mm7";
    read(c, "format", format, path, p);
    if (format == "sbg") {
      m.format = CanImuFormat::kSbg;
    } else if (format == "bosch_mm7") {
      m.format = CanImuFormat::kBoschMm7;
    } else {
      p.add(c["format"], path + ".format", "expected sbg or bosch_mm7");
    }
    if (!(m.noise.rate_hz > 0.0 && m.noise.rate_hz <= 1000.0)) {
      p.add(c["rate_hz"], path + ".rate_hz", "must be within (0, 1000]");
    }
    read_pose(c, path, m.T_body_imu, p);
    s.can_imu = m;
  }
  if (const auto c = root["serial_imu"]) {
    const std::string path = "scenario.serial_imu";
    check_keys(c,
               {"name", "protocol", "rate_hz", "baud_rate", "max_read_bytes", "read_latency_s",
                "corrupt_probability", "noise_probability", "clock", "translation", "rpy_deg"},
               path, p);
    SerialImuMount m = s.serial_imu.value_or(SerialImuMount{});
    read(c, "name", m.name, path, p);
    std::string protocol =
        m.protocol == SerialImuProtocol::kXsensMtData2 ? "xsens_mtdata2" : "vectornav_binary";
    read(c, "protocol", protocol, path, p);
    if (protocol == "xsens_mtdata2") {
      m.protocol = SerialImuProtocol::kXsensMtData2;
    } else if (protocol == "vectornav_binary") {
      m.protocol = SerialImuProtocol::kVectorNavBinary;
    } else {
      p.add(c["protocol"], path + ".protocol", "expected xsens_mtdata2 or vectornav_binary");
    }
    read(c, "rate_hz", m.noise.rate_hz, path, p);
    read(c, "baud_rate", m.baud_rate, path, p);
    read(c, "max_read_bytes", m.max_read_bytes, path, p);
    read(c, "read_latency_s", m.read_latency_s, path, p);
    read(c, "corrupt_probability", m.corrupt_probability, path, p);
    read(c, "noise_probability", m.noise_probability, path, p);
    if (const auto k = c["clock"]) {
      check_keys(k, {"offset_s", "skew_ppm", "jitter_s", "reset_at_s"}, path + ".clock", p);
      read(k, "offset_s", m.clock.offset_s, path + ".clock", p);
      read(k, "skew_ppm", m.clock.skew_ppm, path + ".clock", p);
      read(k, "jitter_s", m.clock.jitter_s, path + ".clock", p);
      read(k, "reset_at_s", m.clock.reset_at_s, path + ".clock", p);
    }
    if (!(m.noise.rate_hz > 0.0 && m.noise.rate_hz <= 2000.0)) {
      p.add(c["rate_hz"], path + ".rate_hz", "must be within (0, 2000]");
    }
    if (m.baud_rate < 9600) p.add(c["baud_rate"], path + ".baud_rate", "must be >= 9600");
    if (m.max_read_bytes < 1) p.add(c["max_read_bytes"], path + ".max_read_bytes", "must be >= 1");
    for (const double q : {m.corrupt_probability, m.noise_probability}) {
      if (q < 0.0 || q > 1.0) p.add(c, path, "probabilities must be within [0, 1]");
    }
    if (m.read_latency_s < 0.0)
      p.add(c["read_latency_s"], path + ".read_latency_s", "must be >= 0");
    read_pose(c, path, m.T_body_imu, p);
    s.serial_imu = m;
  }
  if (s.name.empty()) p.add(root, "scenario.name", "required (or give a base)");
  if (!(std::isfinite(s.duration_s) && s.duration_s > 0.0 && s.duration_s <= 3600.0)) {
    p.add(root["duration_s"], "scenario.duration_s", "must be a number of seconds in (0, 3600]");
  }
  bool body_found = s.can_imu && s.can_imu->name == s.body_imu;
  for (const auto& l : s.lidars) body_found = body_found || l.name == s.body_imu;
  body_found = body_found || (s.serial_imu && s.serial_imu->name == s.body_imu);
  if (!body_found)
    p.add(root["body_imu"], "scenario.body_imu",
          "must name a LiDAR, the CAN IMU or the serial IMU");
  if (!p.empty()) throw Error(file.string() + ": invalid scenario:" + p.text());
  return s;
}

}  // namespace livod::sim
