// Reads `camera:` of a camera sensor: projection model, size, intrinsics and distortion, and the
// capture settings livod applies (docs/drivers/camera.md).

#include <array>
#include <string_view>

#include "daemon/config/readers.hpp"

namespace livod::daemon::config_detail {

namespace {

template <class E>
struct Name {
  std::string_view name;
  E value;
};

constexpr std::array<Name<CameraPixelFormat>, 3> kPixelFormats{{
    {"mono8", CameraPixelFormat::mono8},
    {"mono16", CameraPixelFormat::mono16},
    {"bgr8", CameraPixelFormat::bgr8},
}};
constexpr std::array<Name<CameraTimestamp>, 3> kTimestamps{{
    {"auto", CameraTimestamp::automatic},
    {"start_of_exposure", CameraTimestamp::start_of_exposure},
    {"end_of_frame", CameraTimestamp::end_of_frame},
}};
constexpr std::array<Name<CameraTrigger>, 3> kTriggers{{
    {"free_run", CameraTrigger::free_run},
    {"software", CameraTrigger::software},
    {"hardware", CameraTrigger::hardware},
}};

template <class E, std::size_t N>
bool read_name(MapReader& m, std::string_view key, const std::array<Name<E>, N>& names, E& out) {
  const auto v = m.take(key);
  if (!v || v->node.IsNull()) return false;
  const auto text = parse_string(m.problems(), *v);
  if (!text) return false;
  std::vector<std::string> all;
  for (const auto& n : names) {
    if (n.name == *text) {
      out = n.value;
      return true;
    }
    all.emplace_back(n.name);
  }
  m.problems().error(ProblemKind::invalid_value, v->path, v->at,
                     "'" + *text + "' is not one of: " + join(all) + did_you_mean(*text, all));
  return false;
}

// A V4L2 fourcc as written in the file: 1-4 printable characters ("GREY", "MJPG", "Y16").
bool valid_fourcc(const std::string& s) {
  if (s.empty() || s.size() > 4) return false;
  for (const char c : s) {
    if (c < 0x21 || c > 0x7E) return false;
  }
  return true;
}

void read_v4l2(MapReader& v, CameraConfig& camera) {
  if (const auto f = v.take("formats"); f && !f->node.IsNull()) {
    for (const auto& item : sequence_items(v.problems(), *f)) {
      const auto s = parse_string(v.problems(), item);
      if (!s) continue;
      if (!valid_fourcc(*s)) {
        v.problems().error(ProblemKind::invalid_value, item.path, item.at,
                           "'" + *s + "' is not a fourcc (e.g. GREY, Y16, YUYV, MJPG, BGR3)");
        continue;
      }
      camera.v4l2_formats.push_back(*s);
    }
  }
  v.finish();
}

void read_aravis(MapReader& a, CameraConfig& camera) {
  read_name(a, "trigger", kTriggers, camera.trigger);
  a.read("trigger_line", camera.trigger_line);
  a.read("packet_size", camera.packet_size, 0, 65535);
  if (camera.packet_size != 0 && camera.packet_size < 576) {
    a.problems().error(ProblemKind::out_of_range, a.child_path("packet_size"),
                       a.key_at("packet_size"),
                       "a GigE Vision packet is at least 576 bytes (0 negotiates it)");
  }
  a.read("packet_resend", camera.packet_resend);
  a.read("ptp", camera.ptp);
  a.read("chunk_exposure", camera.chunk_exposure);
  a.finish();
}

}  // namespace

void read_camera(MapReader& c, Driver driver, CameraConfig& camera, bool& ok) {
  ProblemList& problems = c.problems();
  constexpr long long kMaxImageSide_px = 20000;
  ok = true;
  if (const auto v = c.take("model"); v && !v->node.IsNull()) {
    if (auto m = parse_enum<CameraModel>(problems, *v)) {
      camera.model = *m;
    } else {
      ok = false;
    }
  }
  const auto width = c.require("width", "pixels");
  const auto height = c.require("height", "pixels");
  std::optional<long long> w;
  std::optional<long long> h;
  if (width) w = parse_integer(problems, *width, 1, kMaxImageSide_px);
  if (height) h = parse_integer(problems, *height, 1, kMaxImageSide_px);
  if (w) camera.width = static_cast<int>(*w);
  if (h) camera.height = static_cast<int>(*h);
  ok = ok && w && h;

  if (const auto v = c.require("intrinsics", "[fx, fy, cx, cy] in pixels")) {
    const auto k = parse_numbers(problems, *v, 4, 4, closed(0.0, 1e5));
    if (k) {
      for (std::size_t i = 0; i < 4; ++i) camera.intrinsics[i] = (*k)[i];
      if (camera.intrinsics[0] <= 0.0 || camera.intrinsics[1] <= 0.0) {
        problems.error(ProblemKind::out_of_range, v->path, v->at, "fx and fy must be > 0");
        ok = false;
      } else if (w && h &&
                 (camera.intrinsics[2] > static_cast<double>(*w) ||
                  camera.intrinsics[3] > static_cast<double>(*h))) {
        problems.error(ProblemKind::out_of_range, v->path, v->at,
                       "the principal point (" + format_number(camera.intrinsics[2]) + ", " +
                           format_number(camera.intrinsics[3]) + ") lies outside the " +
                           std::to_string(*w) + "x" + std::to_string(*h) + " image");
        ok = false;
      }
    } else {
      ok = false;
    }
  } else {
    ok = false;
  }

  if (const auto v = c.take("distortion"); v && !v->node.IsNull()) {
    const auto d = parse_numbers(problems, *v, 0, 5, closed(-100.0, 100.0));
    if (d) {
      const std::size_t n = d->size();
      const bool valid =
          camera.model == CameraModel::pinhole ? (n == 0 || n == 4 || n == 5) : n == 4;
      if (valid) {
        camera.distortion = *d;
      } else {
        problems.error(ProblemKind::invalid_value, v->path, v->at,
                       camera.model == CameraModel::pinhole
                           ? "pinhole (radial-tangential) distortion has 4 [k1, k2, p1, p2] or 5 "
                             "[k1, k2, p1, p2, k3] coefficients, got " +
                                 std::to_string(n)
                           : "equidistant distortion has 4 coefficients [k1, k2, k3, k4], got " +
                                 std::to_string(n));
        ok = false;
      }
    } else {
      ok = false;
    }
  } else if (camera.model == CameraModel::equidistant) {
    problems.error(ProblemKind::missing_key, c.child_path("distortion"), c.at(),
                   "an equidistant camera needs its 4 coefficients [k1, k2, k3, k4]");
    ok = false;
  }

  if (const auto v = c.take("scale"); v && !v->node.IsNull()) {
    const auto scale = parse_double(problems, *v, left_open(0.0, 1.0));
    if (scale) camera.scale = *scale;
    ok = ok && scale.has_value();
  }
  c.read_optional("exposure_s", camera.exposure_s, left_open(0.0, 1.0));
  c.read_optional("frame_rate_hz", camera.frame_rate_hz, left_open(0.0, 1000.0));
  c.read("decimation", camera.decimation, 1, 1000);

  // Capture settings of live cameras.
  const bool live = driver == Driver::v4l2 || driver == Driver::aravis;
  const char* live_only = "applies to live cameras (v4l2, aravis) only";
  for (const char* key : {"pixel_format", "gain", "buffers", "timestamp", "readout_s"}) {
    if (!live && c.has(key)) {
      problems.error(ProblemKind::inconsistent, c.child_path(key), c.key_at(key),
                     std::string("'") + key + "' " + live_only);
    }
  }
  if (live) {
    read_name(c, "pixel_format", kPixelFormats, camera.pixel_format);
    c.read_optional("gain", camera.gain, closed(-1000.0, 1000.0));
    c.read("buffers", camera.buffers, 2, 64);
    read_name(c, "timestamp", kTimestamps, camera.timestamp);
    c.read("readout_s", camera.readout_s, closed(0.0, 1.0));
    if (camera.readout_s > 0.0 && camera.timestamp == CameraTimestamp::start_of_exposure) {
      problems.warning(ProblemKind::inconsistent, c.child_path("readout_s"), c.key_at("readout_s"),
                       "ignored: start-of-exposure stamps need no readout correction");
    }
  }
  if (const auto v = c.take("v4l2"); v && !v->node.IsNull()) {
    if (driver != Driver::v4l2) {
      problems.error(ProblemKind::inconsistent, v->path, v->at,
                     "'v4l2' applies to v4l2 cameras only");
    } else {
      MapReader r(problems, v->node, v->path, v->at);
      read_v4l2(r, camera);
    }
  }
  if (const auto v = c.take("aravis"); v && !v->node.IsNull()) {
    if (driver != Driver::aravis) {
      problems.error(ProblemKind::inconsistent, v->path, v->at,
                     "'aravis' applies to aravis cameras only");
    } else {
      MapReader r(problems, v->node, v->path, v->at);
      read_aravis(r, camera);
      if (camera.trigger == CameraTrigger::software && !camera.frame_rate_hz) {
        problems.error(ProblemKind::missing_key, c.child_path("frame_rate_hz"), v->at,
                       "a software-triggered camera needs frame_rate_hz: livod fires the "
                       "triggers at that rate");
      }
    }
  }
  if (camera.timestamp == CameraTimestamp::automatic && driver == Driver::aravis &&
      camera.readout_s > 0.0) {
    problems.warning(ProblemKind::inconsistent, c.child_path("readout_s"), c.key_at("readout_s"),
                     "ignored: GenICam cameras are taken to stamp the start of exposure unless "
                     "timestamp: end_of_frame is set");
  }
  c.finish();
}

}  // namespace livod::daemon::config_detail
