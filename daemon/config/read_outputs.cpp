// Reads `outputs:`: the LCM publisher and the files written by a run.

#include <algorithm>
#include <array>
#include <string>
#include <system_error>

#include "daemon/config/readers.hpp"

namespace livod::daemon::config_detail {

namespace {

// LCM 1.3 providers; "udpm" is the network one, the rest are for tests and tools.
constexpr std::array<std::string_view, 5> kLcmProviders = {"udpm://", "mpudpm://", "memq://",
                                                           "file://", "tcpq://"};

// LCM_MAX_CHANNEL_NAME_LENGTH of lcm.h: longer names are refused by lcm_publish.
constexpr std::size_t kLcmMaxChannelLength = 63;

bool is_upper_snake(const std::string& s) {
  return std::all_of(s.begin(), s.end(), [](char c) {
    return (c >= 'A' && c <= 'Z') || (c >= '0' && c <= '9') || c == '_';
  });
}

void check_udpm_group(ProblemList& problems, const Value& v, const std::string& url) {
  // udpm://GROUP:PORT?options
  const std::string rest = url.substr(std::string_view("udpm://").size());
  const std::string address = rest.substr(0, rest.find_first_of(":?"));
  if (address.empty()) return;  // LCM's default group
  if (!is_ipv4(address)) {
    problems.error(ProblemKind::invalid_value, v.path, v.at,
                   "'" + address + "' in the udpm URL is not an IPv4 multicast group");
    return;
  }
  const auto first_octet = std::stoi(address.substr(0, address.find('.')));
  if (first_octet < 224 || first_octet > 239) {
    problems.error(ProblemKind::invalid_value, v.path, v.at,
                   "'" + address + "' in the udpm URL is not a multicast group (224.0.0.0/4)");
  }
}

void read_lcm(ProblemList& problems, const Value& value, LcmOutputConfig& lcm) {
  if (value.node.IsNull()) {  // `lcm: null` switches LCM off, like `trajectory: null`
    lcm.enabled = false;
    return;
  }
  MapReader m(problems, value.node, value.path, value.at);
  m.read("enabled", lcm.enabled);
  if (const auto v = m.take("url"); v && !v->node.IsNull()) {
    if (const auto url = parse_string(problems, *v)) {
      const bool known = std::any_of(kLcmProviders.begin(), kLcmProviders.end(),
                                     [&](std::string_view p) { return url->rfind(p, 0) == 0; });
      if (!known) {
        problems.error(ProblemKind::invalid_value, v->path, v->at,
                       "'" + *url +
                           "' is not an LCM URL (udpm://, mpudpm://, memq://, file://, "
                           "tcpq://)");
      } else {
        lcm.url = *url;
        if (url->rfind("udpm://", 0) == 0) check_udpm_group(problems, *v, *url);
      }
    }
  }
  Position suffix_at = m.at();
  if (const auto v = m.take("channel_suffix"); v && !v->node.IsNull()) {
    suffix_at = v->at;
    if (const auto s = parse_string(problems, *v)) {
      if (is_upper_snake(*s)) {
        lcm.channel_suffix = *s;
      } else {
        problems.error(ProblemKind::invalid_value, v->path, v->at,
                       "channels are UPPER_SNAKE: use A-Z, 0-9 and _ (e.g. _REPLAY)");
      }
    }
  }
  m.read("publish_imu_rate", lcm.publish_imu_rate);
  m.read("publish_cloud", lcm.publish_cloud);
  m.read("cloud_max_points", lcm.cloud_max_points, 100, 10000000);
  m.read("publish_bot_core_pose", lcm.publish_bot_core_pose);

  // channels: {pose, pose_imu, health, cloud, bot_core_pose}
  struct Channel {
    const char* key;
    std::string* name;
    bool used;
    bool ok = true;
    bool given = false;
    std::string path;
    Position at;
  };
  std::array<Channel, 5> channels = {{
      {"pose", &lcm.channels.pose, true},
      {"pose_imu", &lcm.channels.pose_imu, lcm.publish_imu_rate},
      {"health", &lcm.channels.health, true},
      {"cloud", &lcm.channels.cloud, lcm.publish_cloud},
      {"bot_core_pose", &lcm.channels.bot_core_pose, lcm.publish_bot_core_pose},
  }};
  MapReader cm = m.map("channels");
  for (Channel& c : channels) {
    c.path = cm.child_path(c.key);
    const auto v = cm.take(c.key);
    if (!v || v->node.IsNull()) continue;
    c.given = true;
    c.path = v->path;
    c.at = v->at;
    const auto name = parse_string(problems, *v);
    if (!name) {
      c.ok = false;
      continue;
    }
    if (name->empty() || !is_upper_snake(*name)) {
      problems.error(ProblemKind::invalid_value, v->path, v->at,
                     "'" + *name + "' is not an UPPER_SNAKE channel name (A-Z, 0-9, _)");
      c.ok = false;
      continue;
    }
    *c.name = *name;
  }
  cm.finish();
  m.finish();

  // Too long with the suffix: reported on the channel when it was given, else once on the suffix.
  std::string too_long_defaults;
  for (std::size_t i = 0; i < channels.size(); ++i) {
    const Channel& c = channels[i];
    if (!c.ok) continue;
    const std::string full = lcm.channel(*c.name);
    if (full.size() > kLcmMaxChannelLength) {
      if (c.given) {
        problems.error(ProblemKind::out_of_range, c.path, c.at,
                       "channel '" + full + "' (with the suffix) is " +
                           std::to_string(full.size()) + " bytes; LCM allows " +
                           std::to_string(kLcmMaxChannelLength));
      } else {
        too_long_defaults += (too_long_defaults.empty() ? "" : ", ") + full;
      }
    }
    if (!c.used) continue;
    for (std::size_t j = 0; j < i; ++j) {
      if (channels[j].ok && channels[j].used && *channels[j].name == *c.name) {
        problems.error(ProblemKind::inconsistent, c.path, c.at,
                       "'" + *c.name + "' is also the " + channels[j].key +
                           " channel: two message types on one channel break subscribers");
      }
    }
  }
  if (!too_long_defaults.empty()) {
    problems.error(ProblemKind::out_of_range, m.child_path("channel_suffix"), suffix_at,
                   "makes channel names longer than LCM's " + std::to_string(kLcmMaxChannelLength) +
                       " bytes: " + too_long_defaults);
  }
}

// An output file: null = none. Its folder must exist (livod does not create folders: a typo in
// a path should not silently grow a new tree, e.g. under /).
void read_output_file(MapReader& m, const ReadContext& context, std::string_view key,
                      std::filesystem::path& out) {
  const auto v = m.take(key);
  if (!v) return;
  const auto text = parse_string(m.problems(), *v, true);
  if (!text || text->empty()) return;
  out = resolve_path(context, *text);
  std::error_code ec;
  const auto folder = out.parent_path();
  if (!folder.empty() && !std::filesystem::is_directory(folder, ec)) {
    m.problems().warning(ProblemKind::missing_file, v->path, v->at,
                         "folder '" + folder.string() + "' does not exist (yet)");
  }
  if (std::filesystem::is_directory(out, ec)) {
    m.problems().error(ProblemKind::invalid_value, v->path, v->at,
                       "'" + out.string() + "' is a folder; give a file name");
    out.clear();
  }
}

}  // namespace

void read_outputs(MapReader& reader, const ReadContext& context, OutputsConfig& outputs) {
  if (const auto v = reader.take("lcm")) read_lcm(reader.problems(), *v, outputs.lcm);
  read_output_file(reader, context, "trajectory", outputs.trajectory);
  read_output_file(reader, context, "map_pcd", outputs.map_pcd);
  read_output_file(reader, context, "timing_report", outputs.timing_report);
  const std::array<std::pair<const char*, const std::filesystem::path*>, 3> files = {{
      {"trajectory", &outputs.trajectory},
      {"map_pcd", &outputs.map_pcd},
      {"timing_report", &outputs.timing_report},
  }};
  for (std::size_t i = 0; i < files.size(); ++i) {
    for (std::size_t j = 0; j < i; ++j) {
      if (!files[i].second->empty() && *files[i].second == *files[j].second) {
        reader.problems().error(ProblemKind::inconsistent, reader.child_path(files[i].first),
                                reader.key_at(files[i].first),
                                "writes to the same file as " + std::string(files[j].first));
      }
    }
  }
  reader.finish();
}

}  // namespace livod::daemon::config_detail
