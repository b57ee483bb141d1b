// Reads one entry of `sensors:`: the generic keys, the source and the driver-specific sections.

#include <arpa/inet.h>

#include <algorithm>
#include <cctype>
#include <system_error>

#include "core/error.hpp"
#include "daemon/config/readers.hpp"
#include "daemon/config/sensor_models.hpp"
#include "drivers/imu/serial_port.hpp"

namespace livod::daemon::config_detail {

namespace {

constexpr std::size_t kMaxNameLength = 32;
constexpr int kLowestUnprivilegedPort = 1024;

std::vector<std::string> names_of(const std::vector<ReplayFormat>& formats) {
  std::vector<std::string> names;
  for (auto f : formats) names.emplace_back(enum_name(f));
  return names;
}

// "ouster, livox_sdk1 (AVIA, HORIZON, TELE-15), ..., velodyne HDL-32E": who has an IMU.
std::string internal_imu_models() {
  std::string out;
  for (const drivers::LidarFamily* f : drivers::lidar_families()) {
    std::string with;
    bool all = true;
    for (const auto& model : f->models) {
      if (model.internal_imu) {
        with += (with.empty() ? "" : ", ") + std::string(model.name);
      } else {
        all = false;
      }
    }
    if (with.empty()) continue;
    out += (out.empty() ? "" : "; ") + std::string(f->driver) + (all ? "" : " " + with);
  }
  return out;
}

// " (of the velodyne models only the HDL-32E has one)", or "" when none has.
std::string imu_models_of(const drivers::LidarFamily* family) {
  if (family == nullptr) return {};
  std::vector<std::string> with;
  for (const auto& model : family->models) {
    if (model.internal_imu) with.emplace_back(model.name);
  }
  if (with.empty()) return " (no " + std::string(family->driver) + " model has one)";
  std::string list;
  for (std::size_t i = 0; i < with.size(); ++i) list += (i == 0 ? "" : ", ") + with[i];
  return " (of the " + std::string(family->driver) + " models only the " + list +
         (with.size() == 1 ? " has one)" : " have one)");
}

std::string packet_lidar_drivers() {
  std::string out;
  for (const drivers::LidarFamily* f : drivers::lidar_families()) {
    if (!out.empty()) out += ", ";
    out += f->driver;
  }
  return out;
}

bool valid_sensor_name(const std::string& name) {
  if (name.empty() || name.size() > kMaxNameLength) return false;
  return std::all_of(name.begin(), name.end(), [](char c) {
    return (c >= 'a' && c <= 'z') || (c >= '0' && c <= '9') || c == '_';
  });
}

// Declares `key`; when it is present although it does not apply to this driver, reports it once
// (without looking inside) and returns nothing.
std::optional<Value> take_applicable(MapReader& m, std::string_view key, bool applies,
                                     std::string_view applies_to) {
  auto v = m.take(key);
  if (!v) return std::nullopt;
  if (!applies) {
    m.problems().error(
        ProblemKind::inconsistent, v->path, v->at,
        "'" + std::string(key) + "' applies to " + std::string(applies_to) + " only");
    return std::nullopt;
  }
  return v;
}

std::optional<std::string> read_model(MapReader& m, Driver driver) {
  const auto models = known_models(driver);
  auto v = model_required(driver) ? m.require("model", "one of: " + join(models)) : m.take("model");
  if (!v || v->node.IsNull()) return std::nullopt;
  const auto text = parse_string(m.problems(), *v);
  if (!text) return std::nullopt;
  if (auto canonical = canonical_model(driver, *text)) return canonical;
  m.problems().error(ProblemKind::invalid_value, v->path, v->at,
                     "unknown " + std::string(enum_name(driver)) + " model '" + *text +
                         "'; expected one of: " + join(models) + did_you_mean(*text, models));
  return std::nullopt;
}

void check_file(ProblemList& problems, const Value& v, const std::filesystem::path& file,
                std::string_view what) {
  std::error_code ec;
  const auto status = std::filesystem::status(file, ec);
  if (!std::filesystem::exists(status)) {
    problems.error(ProblemKind::missing_file, v.path, v.at,
                   std::string(what) + " '" + file.string() + "' does not exist");
  } else if (!std::filesystem::is_regular_file(status)) {
    problems.error(ProblemKind::invalid_value, v.path, v.at,
                   std::string(what) + " '" + file.string() + "' is not a regular file");
  }
}

// A LiDAR family's own section, read by the family (drivers::LidarFamily::read_settings).
class SectionSettings final : public drivers::SettingsReader {
 public:
  explicit SectionSettings(MapReader& section) : m_(section) {}

  std::optional<std::array<double, 2>> degree_pair(std::string_view key) override {
    const auto v = m_.take(key);
    if (!v || v->node.IsNull()) return std::nullopt;
    const auto numbers = parse_numbers(m_.problems(), *v, 2, 2, closed(0.0, 360.0));
    if (!numbers) return std::nullopt;
    return std::array<double, 2>{(*numbers)[0], (*numbers)[1]};
  }

  std::optional<double> number(std::string_view key, double min, double max) override {
    std::optional<double> out;
    m_.read_optional(key, out, closed(min, max));
    return out;
  }

  void error(std::string_view key, const std::string& message) override {
    m_.problems().error(ProblemKind::invalid_value, m_.child_path(key), m_.key_at(key), message);
  }

 private:
  MapReader& m_;
};

// The families that take a file of the given kind, for messages ("velodyne and hesai sensors").
std::string families_taking(bool (*takes)(drivers::DecoderFile)) {
  std::vector<std::string> names;
  for (const drivers::LidarFamily* f : drivers::lidar_families()) {
    if (takes(f->file)) names.emplace_back(f->driver);
  }
  std::string out;
  for (std::size_t i = 0; i < names.size(); ++i) {
    out += (i == 0 ? "" : (i + 1 == names.size() ? " and " : ", ")) + names[i];
  }
  return out + " sensors";
}

bool takes_calibration(drivers::DecoderFile f) {
  return f == drivers::DecoderFile::kCalibrationOptional ||
         f == drivers::DecoderFile::kCalibrationRequired;
}

bool takes_metadata(drivers::DecoderFile f) {
  return f == drivers::DecoderFile::kMetadata;
}

// ---- source.udp -------------------------------------------------------------------------------

std::uint16_t& port_slot(UdpPorts& ports, std::size_t index) {
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

bool read_udp(MapReader& u, Driver driver, const std::string& model, UdpSourceConfig& udp,
              SensorSite& site) {
  ProblemList& problems = u.problems();
  bool ok = true;
  udp.ports = default_ports(driver, model);
  if (const auto v = u.take("bind_address"); v && !v->node.IsNull()) {
    site.bind_address_path = v->path;
    if (const auto s = parse_string(problems, *v)) {
      if (is_ipv4(*s)) {
        udp.bind_address = *s;
      } else {
        problems.error(ProblemKind::invalid_value, v->path, v->at,
                       "'" + *s + "' is not an IPv4 address (use 0.0.0.0 for all interfaces)");
        ok = false;
      }
    }
  }
  if (const auto v = u.take("sensor_address"); v && !v->node.IsNull()) {
    if (const auto s = parse_string(problems, *v)) {
      if (is_ipv4(*s) || is_host_name(*s)) {
        udp.sensor_address = *s;
      } else {
        problems.error(ProblemKind::invalid_value, v->path, v->at,
                       "'" + *s + "' is neither an IPv4 address nor a host name");
      }
    }
  }
  if (const auto v = u.take("multicast_group"); v && !v->node.IsNull()) {
    if (const auto s = parse_string(problems, *v)) {
      in_addr addr{};
      if (inet_pton(AF_INET, s->c_str(), &addr) == 1 && (ntohl(addr.s_addr) >> 28) == 0xE) {
        udp.multicast_group = *s;
      } else {
        problems.error(ProblemKind::invalid_value, v->path, v->at,
                       "'" + *s + "' is not an IPv4 multicast address (224.0.0.0/4)");
      }
    }
  }
  u.read("socket_buffer_bytes", udp.socket_buffer_bytes, 64 * 1024, 1024LL * 1024 * 1024);

  const auto names = port_names(driver);
  MapReader p = u.map("ports");
  for (std::size_t i = 0; i < kPortNames.size(); ++i) {
    site.port_at[i] = p.ok() ? p.at() : u.at();
    const auto v = p.take(kPortNames[i]);
    if (!v) continue;
    if (std::find(names.begin(), names.end(), kPortNames[i]) == names.end()) {
      // The HDL-32E's IMU has no port of its own: its words come in the position packets.
      const std::string hint =
          driver == Driver::velodyne && std::string_view(kPortNames[i]) == "imu"
              ? "; the HDL-32E's internal IMU arrives in its position "
                "packets, on the 'position' port"
              : "";
      problems.error(ProblemKind::inconsistent, v->path, v->at,
                     std::string(enum_name(driver)) + " sensors have no '" + kPortNames[i] +
                         "' stream (their ports: " + join(names) + ")" + hint);
      continue;
    }
    const auto port = parse_integer(problems, *v, 1, 65535);
    if (!port) {
      site.port_invalid[i] = true;
      continue;
    }
    port_slot(udp.ports, i) = static_cast<std::uint16_t>(*port);
    site.port_at[i] = v->at;
    site.port_given[i] = true;
    if (*port < kLowestUnprivilegedPort) {
      problems.warning(ProblemKind::out_of_range, v->path, v->at,
                       "port " + std::to_string(*port) +
                           " is privileged: binding it needs CAP_NET_BIND_SERVICE");
    }
  }
  p.finish();
  return ok;
}

// ---- source.replay ----------------------------------------------------------------------------

std::optional<ReplayFormat> format_from_extension(const std::filesystem::path& file) {
  std::string ext = file.extension().string();
  for (auto& c : ext) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
  if (ext == ".pcap" || ext == ".pcapng") return ReplayFormat::pcap;
  if (ext == ".log" || ext == ".candump") return ReplayFormat::candump;
  if (ext == ".bag") return ReplayFormat::rosbag1;
  if (ext == ".serial") return ReplayFormat::serial;  // io/serial_capture.hpp
  if (ext.empty()) return ReplayFormat::euroc;        // a folder
  return std::nullopt;
}

bool read_replay(MapReader& r, Driver driver, const ReadContext& context,
                 ReplaySourceConfig& replay) {
  ProblemList& problems = r.problems();
  bool ok = true;
  const auto file_value = r.require("file", "the recording to replay");
  std::optional<std::string> file_text;
  if (file_value) file_text = parse_string(problems, *file_value);
  if (file_text) replay.file = resolve_path(context, *file_text);
  ok = ok && file_text.has_value();

  std::optional<ReplayFormat> format;
  const auto format_value = r.take("format");
  if (format_value && !format_value->node.IsNull()) {
    format = parse_enum<ReplayFormat>(problems, *format_value);
    ok = ok && format.has_value();
  } else if (file_text) {
    format = format_from_extension(replay.file);
    if (!format) {
      problems.error(ProblemKind::invalid_value, r.child_path("format"), file_value->at,
                     "cannot tell the format of '" + replay.file.filename().string() +
                         "' from its extension; set 'format' (one of: pcap, candump, rosbag1, "
                         "euroc, serial)");
      ok = false;
    }
  }

  std::string topic;
  const bool has_topic = r.read("topic", topic) && !topic.empty();
  if (format) {
    replay.format = *format;
    const auto allowed = replay_formats(driver);
    if (std::find(allowed.begin(), allowed.end(), *format) == allowed.end()) {
      const Value& where = format_value ? *format_value : *file_value;
      problems.error(ProblemKind::inconsistent, r.child_path("format"), where.at,
                     "a " + std::string(enum_name(*format)) + " recording does not carry " +
                         std::string(enum_name(driver)) + " data (" +
                         (allowed.empty() ? std::string("this driver is live only")
                                          : "use one of: " + join(names_of(allowed))) +
                         ")");
      ok = false;
    } else if (*format == ReplayFormat::rosbag1 && !has_topic) {
      problems.error(ProblemKind::missing_key, r.child_path("topic"), r.at(),
                     "a rosbag1 replay needs the 'topic' to read");
      ok = false;
    } else if (*format != ReplayFormat::rosbag1 && has_topic) {
      problems.error(ProblemKind::inconsistent, r.child_path("topic"), r.key_at("topic"),
                     "'topic' applies to rosbag1 replays only");
    }
  }
  replay.topic = topic;

  if (file_text && format && ok) {
    // A missing recording is a warning: configs are often checked on another machine than the
    // one holding the captures, and `livod replay` takes capture paths on its command line. The
    // replay reader fails with an error when it cannot open the file.
    std::error_code ec;
    const auto status = std::filesystem::status(replay.file, ec);
    const bool wants_folder = *format == ReplayFormat::euroc;
    if (!std::filesystem::exists(status)) {
      problems.warning(ProblemKind::missing_file, file_value->path, file_value->at,
                       std::string(wants_folder ? "replay folder '" : "replay file '") +
                           replay.file.string() + "' does not exist");
    } else if (wants_folder && !std::filesystem::is_directory(status)) {
      problems.error(ProblemKind::invalid_value, file_value->path, file_value->at,
                     "an euroc replay reads a folder (e.g. mav0/cam0), '" + replay.file.string() +
                         "' is a file");
      ok = false;
    } else if (!wants_folder && std::filesystem::is_directory(status)) {
      problems.error(ProblemKind::invalid_value, file_value->path, file_value->at,
                     "'" + replay.file.string() + "' is a folder, not a " +
                         std::string(enum_name(*format)) + " file");
      ok = false;
    }
  }
  r.finish();
  return ok;
}

// ---- source.device ----------------------------------------------------------------------------

bool valid_interface_name(const std::string& name) {
  constexpr std::size_t kMaxInterfaceName = 15;  // IFNAMSIZ - 1
  if (name.empty() || name.size() > kMaxInterfaceName) return false;
  return std::none_of(name.begin(), name.end(), [](char c) {
    return c == '/' || std::isspace(static_cast<unsigned char>(c)) != 0;
  });
}

bool read_device(MapReader& d, Driver driver, DeviceSourceConfig& device) {
  ProblemList& problems = d.problems();
  bool ok = true;
  const bool uses_path = driver == Driver::v4l2 || driver == Driver::serial_imu;
  if (uses_path) {
    if (const auto v = d.require("path", "the device node, e.g. /dev/video0 or /dev/ttyUSB0")) {
      const auto s = parse_string(problems, *v);
      if (s) device.path = *s;
      ok = ok && s.has_value();
      if (s && driver == Driver::serial_imu && s->rfind("usb:", 0) == 0) {
        try {
          (void)imu::parse_usb_selector(*s);  // usb:VVVV:PPPP[:SERIAL] selects a libusb device
        } catch (const Error& e) {
          problems.error(ProblemKind::invalid_value, v->path, v->at, e.what());
          ok = false;
        }
      }
    } else {
      ok = false;
    }
  } else if (const auto v = d.take("path")) {
    problems.error(ProblemKind::inconsistent, v->path, v->at,
                   "'path' applies to v4l2 and serial_imu devices only");
  }

  if (const auto v = take_applicable(d, "camera_id", driver == Driver::aravis, "aravis cameras")) {
    if (const auto s = parse_string(problems, *v, true)) device.camera_id = *s;
  }

  if (driver == Driver::can_imu) {
    if (const auto v = d.require("interface", "the SocketCAN interface, e.g. can0")) {
      const auto s = parse_string(problems, *v);
      if (s && valid_interface_name(*s)) {
        device.interface = *s;
      } else {
        if (s) {
          problems.error(ProblemKind::invalid_value, v->path, v->at,
                         "'" + *s + "' is not a network interface name");
        }
        ok = false;
      }
    } else {
      ok = false;
    }
  } else if (const auto v = d.take("interface")) {
    problems.error(ProblemKind::inconsistent, v->path, v->at,
                   "'interface' applies to can_imu devices only");
  }
  d.finish();
  return ok;
}

void read_source(MapReader& m, Driver driver, const std::string& model, const ReadContext& context,
                 SensorConfig& sensor, SensorSite& site) {
  ProblemList& problems = m.problems();
  const auto v = m.require("source", "exactly one of: udp, replay, device");
  if (!v) return;
  MapReader s(problems, v->node, v->path, v->at, false);
  if (!s.ok()) return;
  const auto udp = s.take("udp");
  const auto replay = s.take("replay");
  const auto device = s.take("device");
  s.finish();
  const int count = (udp ? 1 : 0) + (replay ? 1 : 0) + (device ? 1 : 0);
  if (count == 0) {
    problems.error(ProblemKind::missing_key, v->path, v->at,
                   "needs exactly one of: udp, replay, device");
    return;
  }
  if (count > 1) {
    problems.error(ProblemKind::inconsistent, v->path, v->at,
                   "has more than one of udp, replay, device; give exactly one");
    return;
  }
  if (udp) {
    if (!supports_udp(driver)) {
      problems.error(ProblemKind::inconsistent, udp->path, udp->at,
                     std::string(enum_name(driver)) + " sensors do not receive UDP");
      return;
    }
    MapReader u(problems, udp->node, udp->path, udp->at);
    UdpSourceConfig config;
    site.source_ok = read_udp(u, driver, model, config, site);
    u.finish();
    sensor.source = config;
  } else if (replay) {
    MapReader r(problems, replay->node, replay->path, replay->at, false);
    if (!r.ok()) return;
    ReplaySourceConfig config;
    site.source_ok = read_replay(r, driver, context, config);
    site.is_replay = true;
    sensor.source = config;
  } else {
    if (!supports_device(driver)) {
      problems.error(ProblemKind::inconsistent, device->path, device->at,
                     std::string(enum_name(driver)) + " sensors have no local device (use " +
                         (supports_udp(driver) ? "udp or replay)" : "replay)"));
      return;
    }
    MapReader d(problems, device->node, device->path, device->at, false);
    if (!d.ok()) return;
    DeviceSourceConfig config;
    site.source_ok = read_device(d, driver, config);
    sensor.source = config;
  }
}

// ---- other sections ---------------------------------------------------------------------------

void read_frame_cut(MapReader& f, Driver driver, FrameCutConfig& cut) {
  ProblemList& problems = f.problems();
  cut.mode = default_frame_cut(driver);
  if (f.read_enum("mode", cut.mode)) {
    const auto allowed = allowed_frame_cuts(driver);
    if (std::find(allowed.begin(), allowed.end(), cut.mode) == allowed.end()) {
      std::vector<std::string> names;
      for (auto m : allowed) names.emplace_back(enum_name(m));
      problems.error(ProblemKind::inconsistent, f.child_path("mode"), f.key_at("mode"),
                     "mode '" + std::string(enum_name(cut.mode)) + "' is not available for " +
                         std::string(enum_name(driver)) + " (use: " + join(names) + ")");
    }
  }
  if (f.read("azimuth_deg", cut.azimuth_deg, right_open(0.0, 360.0)) &&
      cut.mode != FrameCutMode::azimuth) {
    problems.warning(ProblemKind::inconsistent, f.child_path("azimuth_deg"),
                     f.key_at("azimuth_deg"), "ignored: used only with mode azimuth");
  }
  if (f.read("period_s", cut.period_s, closed(0.01, 1.0)) && cut.mode != FrameCutMode::time) {
    problems.warning(ProblemKind::inconsistent, f.child_path("period_s"), f.key_at("period_s"),
                     "ignored: used only with mode time");
  }
  f.finish();
}

void read_clock(MapReader& c, ClockConfig& clock) {
  c.read_enum("mode", clock.mode);
  if (c.read("latency_s", clock.latency_s, closed(0.0, 1.0)) && clock.latency_s != 0.0 &&
      clock.mode != ClockMode::receive_time && clock.mode != ClockMode::automatic) {
    c.problems().warning(ProblemKind::inconsistent, c.child_path("latency_s"),
                         c.key_at("latency_s"),
                         "ignored: used only with mode receive_time (or auto when it falls back "
                         "to receive time)");
  }
  c.read("window_s", clock.window_s, closed(1.0, 3600.0));
  c.read("max_skew_ppm", clock.max_skew_ppm, left_open(0.0, 10000.0));
  c.finish();
}

void read_serial(MapReader& s, SerialConfig& serial) {
  if (const auto v = s.require("protocol", "xsens_mtdata2 or vectornav_binary")) {
    if (const auto p = parse_enum<SerialProtocol>(s.problems(), *v)) serial.protocol = *p;
  }
  if (const auto v = s.take("baud_rate"); v && !v->node.IsNull()) {
    static constexpr std::array<long long, 12> kBaudRates = {9600,    19200,   38400,   57600,
                                                             115200,  230400,  460800,  921600,
                                                             1000000, 2000000, 3000000, 4000000};
    if (const auto b = parse_integer(s.problems(), *v, 1, 100000000)) {
      if (std::find(kBaudRates.begin(), kBaudRates.end(), *b) == kBaudRates.end()) {
        s.problems().error(ProblemKind::invalid_value, v->path, v->at,
                           std::to_string(*b) + " is not a standard baud rate (9600 ... 4000000)");
      } else {
        serial.baud_rate = static_cast<int>(*b);
      }
    }
  }
  s.finish();
}

void read_dataset(MapReader& d, Driver driver, DatasetConfig& dataset) {
  const bool lidar = driver == Driver::dataset_lidar;
  const bool imu = driver == Driver::dataset_imu;
  if (const auto v = take_applicable(d, "time_field", lidar, "dataset_lidar sensors")) {
    if (const auto s = parse_string(d.problems(), *v)) dataset.time_field = *s;
  }
  for (const char* key : {"time_unit", "time_reference", "stamp"}) {
    const auto v = take_applicable(d, key, lidar, "dataset_lidar sensors");
    if (!v || v->node.IsNull()) continue;
    const std::string k = key;
    if (k == "time_unit") {
      if (auto e = parse_enum<TimeUnit>(d.problems(), *v)) dataset.time_unit = *e;
    } else if (k == "time_reference") {
      if (auto e = parse_enum<TimeReference>(d.problems(), *v)) dataset.time_reference = *e;
    } else if (auto e = parse_enum<ScanStamp>(d.problems(), *v)) {
      dataset.stamp = *e;
    }
  }
  if (const auto v = take_applicable(d, "accel_unit", imu, "dataset_imu sensors")) {
    if (auto e = parse_enum<CanUnit>(d.problems(), *v)) {
      if (*e == CanUnit::m_s2 || *e == CanUnit::g) {
        dataset.accel_unit = *e;
      } else {
        d.problems().error(ProblemKind::invalid_value, v->path, v->at,
                           "an acceleration unit is m_s2 or g");
      }
    }
  }
  if (const auto v = take_applicable(d, "gyro_unit", imu, "dataset_imu sensors")) {
    if (auto e = parse_enum<CanUnit>(d.problems(), *v)) {
      if (*e == CanUnit::rad_s || *e == CanUnit::deg_s) {
        dataset.gyro_unit = *e;
      } else {
        d.problems().error(ProblemKind::invalid_value, v->path, v->at,
                           "an angular rate unit is rad_s or deg_s");
      }
    }
  }
  d.finish();
}

// The sections whose applicability depends on the driver; with an unknown driver they are only
// declared, so that one wrong driver name gives one problem.
constexpr std::array<const char*, 10> kDriverSections = {
    "source", "metadata", "calibration", "frame_cut", "imu",
    "lio",    "camera",   "can",         "serial",    "dataset"};

// A LiDAR's own point settings in the estimator (docs/configuration.md, "`lio`" of a sensor):
// the same ranges as estimator.lio's keys.
void read_lidar_lio(MapReader& m, SensorConfig& sensor) {
  estimator::LidarLioParams& lio = sensor.lio;
  double dept_err = 0.0;
  if (m.read("dept_err", dept_err, left_open(0.0, 1.0))) lio.dept_err = dept_err;
  double beam_err_deg = 0.0;
  if (m.read("beam_err_deg", beam_err_deg, left_open(0.0, 5.0))) lio.beam_err_deg = beam_err_deg;
  int point_filter_num = 1;
  if (m.read("point_filter_num", point_filter_num, 1, 1000))
    lio.point_filter_num = point_filter_num;
  double sigma_num = 0.0;
  if (m.read("sigma_num", sigma_num, left_open(0.0, 10.0))) lio.sigma_num = sigma_num;
  sensor.lio_build_map_given = m.read("build_map", lio.build_map);
  m.finish();
}

}  // namespace

std::filesystem::path resolve_path(const ReadContext& context, const std::string& text) {
  std::filesystem::path p(text);
  if (p.is_relative() && !context.base_dir.empty()) p = context.base_dir / p;
  return p.lexically_normal();
}

bool is_ipv4(const std::string& text) {
  in_addr addr{};
  return inet_pton(AF_INET, text.c_str(), &addr) == 1;
}

bool is_host_name(const std::string& text) {
  constexpr std::size_t kMaxHostName = 253;
  if (text.empty() || text.size() > kMaxHostName || text.front() == '-' || text.front() == '.') {
    return false;
  }
  // All-digit-and-dot names would be malformed IPv4 addresses, not host names.
  const bool has_letter = std::any_of(text.begin(), text.end(), [](char c) {
    return std::isalpha(static_cast<unsigned char>(c)) != 0;
  });
  return has_letter && std::all_of(text.begin(), text.end(), [](char c) {
           return std::isalnum(static_cast<unsigned char>(c)) != 0 || c == '-' || c == '.';
         });
}

void read_sensor(ProblemList& problems, const Value& item, const ReadContext& context,
                 SensorConfig& sensor, SensorSite& site) {
  site.path = item.path;
  site.at = item.at;
  MapReader m(problems, item.node, item.path, item.at, false);
  if (!m.ok()) return;
  site.readable = true;
  sensor.line = item.at.line;

  if (const auto v = m.require("name", "[a-z0-9_]+")) {
    site.name_at = v->at;
    if (const auto s = parse_string(problems, *v)) {
      if (*s == "body") {
        problems.error(ProblemKind::invalid_value, v->path, v->at,
                       "'body' is reserved for the body frame (extrinsic.relative_to: body)");
      } else if (valid_sensor_name(*s)) {
        sensor.name = *s;
        site.name_ok = true;
      } else {
        problems.error(ProblemKind::invalid_value, v->path, v->at,
                       "'" + *s + "' is not a valid sensor name (1 to 32 of a-z, 0-9, _)");
      }
    }
  }

  std::optional<Driver> driver;
  {
    std::vector<std::string> names;
    for (const auto& e : enum_entries<Driver>()) names.emplace_back(e.name);
    if (const auto v = m.require("driver", "one of: " + join(names))) {
      driver = parse_enum<Driver>(problems, *v);
    }
  }
  site.driver_known = driver.has_value();

  m.read("enabled", sensor.enabled);
  m.read("time_offset_s", sensor.time_offset_s, closed(-1.0, 1.0));
  {
    MapReader c = m.map("clock");
    read_clock(c, sensor.clock);
  }
  if (const auto v = m.take("extrinsic"); v) {
    site.has_extrinsic_key = true;
    site.extrinsic_at = v->at;
    MapReader e(problems, v->node, v->path, v->at, false);
    if (e.ok()) read_extrinsic(e, sensor, site);
  }

  if (!driver) {
    m.take("model");
    m.take("ring_capacity");
    for (const char* key : kDriverSections) m.take(key);
    for (const drivers::LidarFamily* f : drivers::lidar_families()) {
      if (f->read_settings != nullptr) m.take(f->driver);
    }
    m.finish();
    return;
  }
  sensor.driver = *driver;
  const SensorKind kind = sensor_kind(*driver);
  if (auto model = read_model(m, *driver)) sensor.model = *model;

  sensor.ring_capacity = default_ring_capacity(kind);
  m.read("ring_capacity", sensor.ring_capacity, 2, 1 << 20);

  read_source(m, *driver, sensor.model, context, sensor, site);

  const bool packet_lidar = is_packet_lidar(*driver);
  const drivers::LidarFamily* family = lidar_family(*driver);
  const drivers::DecoderFile file = family ? family->file : drivers::DecoderFile::kNone;
  if (const auto v =
          take_applicable(m, "metadata", takes_metadata(file), families_taking(&takes_metadata))) {
    if (const auto s = parse_string(problems, *v, true)) {
      sensor.metadata = resolve_path(context, *s);
      check_file(problems, *v, sensor.metadata, "metadata file");
    }
  }
  if (const auto v = take_applicable(m, "calibration", takes_calibration(file),
                                     families_taking(&takes_calibration))) {
    if (const auto s = parse_string(problems, *v, true)) {
      sensor.calibration = resolve_path(context, *s);
      check_file(problems, *v, sensor.calibration, "calibration file");
    }
  }
  if (file == drivers::DecoderFile::kCalibrationRequired && sensor.calibration.empty() &&
      !m.has("calibration")) {
    problems.error(ProblemKind::missing_key, m.child_path("calibration"), m.at(),
                   "a " + std::string(enum_name(*driver)) +
                       " sensor needs its angle correction file ('calibration': the CSV the "
                       "sensor's web interface or PandarView exports; every unit differs)");
  }
  // The families' own sections: the sensor's family reads its own, the others are misplaced.
  for (const drivers::LidarFamily* f : drivers::lidar_families()) {
    if (f->read_settings == nullptr) continue;
    if (const auto v =
            take_applicable(m, f->driver, f == family, std::string(f->driver) + " sensors")) {
      MapReader section(problems, v->node, v->path, v->at);
      SectionSettings reader(section);
      f->read_settings(reader, sensor.lidar_settings);
      section.finish();
    }
  }
  if (*driver == Driver::ouster && sensor.metadata.empty() && site.source_ok) {
    if (const auto* udp = std::get_if<UdpSourceConfig>(&sensor.source);
        udp != nullptr && udp->sensor_address.empty()) {
      problems.error(ProblemKind::inconsistent, m.child_path("metadata"), m.key_at("source"),
                     "an ouster sensor needs its metadata: give 'metadata' (a JSON file) or "
                     "'source.udp.sensor_address' to fetch it over HTTP");
    }
    if (const auto* replay = std::get_if<ReplaySourceConfig>(&sensor.source);
        replay != nullptr && replay->format == ReplayFormat::pcap) {
      problems.error(ProblemKind::missing_key, m.child_path("metadata"), m.key_at("source"),
                     "replaying an ouster pcap needs the sensor's metadata JSON (pcaps do not "
                     "carry it)");
    }
  }

  sensor.frame_cut.mode = default_frame_cut(*driver);
  if (const auto v =
          take_applicable(m, "frame_cut", packet_lidar,
                          "LiDARs decoded from packets (" + packet_lidar_drivers() + ")")) {
    MapReader f(problems, v->node, v->path, v->at);
    read_frame_cut(f, *driver, sensor.frame_cut);
  }

  const bool can_have_imu = driver_has_internal_imu_models(*driver);
  sensor.imu.enabled = can_have_imu && model_has_internal_imu(*driver, sensor.model);
  if (const auto v = take_applicable(
          m, "imu", can_have_imu, "LiDARs with an internal IMU (" + internal_imu_models() + ")")) {
    MapReader i(problems, v->node, v->path, v->at);
    bool enabled = sensor.imu.enabled;
    if (i.read("enabled", enabled)) {
      if (enabled && !model_has_internal_imu(*driver, sensor.model)) {
        problems.error(ProblemKind::inconsistent, i.child_path("enabled"), i.key_at("enabled"),
                       "the " + sensor.model + " has no internal IMU" + imu_models_of(family));
      } else {
        sensor.imu.enabled = enabled;
      }
    }
    i.finish();
  }

  if (const auto v = take_applicable(m, "lio", kind == SensorKind::lidar, "LiDARs")) {
    MapReader l(problems, v->node, v->path, v->at);
    read_lidar_lio(l, sensor);
  }

  const bool camera = kind == SensorKind::camera;
  if (camera) {
    if (const auto v = m.require("camera", "model, size and intrinsics")) {
      site.camera_at = v->at;
      MapReader c(problems, v->node, v->path, v->at, false);
      if (c.ok()) read_camera(c, *driver, sensor.camera, site.camera_ok);
    }
  } else {
    take_applicable(m, "camera", false, "cameras (v4l2, aravis, dataset_camera)");
  }

  if (*driver == Driver::can_imu) {
    if (const auto v = m.require("can", "the frame decoder")) {
      MapReader c(problems, v->node, v->path, v->at, false);
      if (c.ok()) read_can(c, sensor.can);
    }
  } else {
    take_applicable(m, "can", false, "can_imu sensors");
  }

  if (*driver == Driver::serial_imu) {
    if (const auto v = m.require("serial", "the protocol")) {
      MapReader s(problems, v->node, v->path, v->at, false);
      if (s.ok()) read_serial(s, sensor.serial);
    }
  } else {
    take_applicable(m, "serial", false, "serial_imu sensors");
  }

  const bool dataset_section = *driver == Driver::dataset_lidar || *driver == Driver::dataset_imu;
  if (const auto v =
          take_applicable(m, "dataset", dataset_section, "dataset_lidar and dataset_imu sensors")) {
    MapReader d(problems, v->node, v->path, v->at);
    read_dataset(d, *driver, sensor.dataset);
  }
  m.finish();
}

}  // namespace livod::daemon::config_detail
