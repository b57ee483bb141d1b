#include "daemon/config/load_config.hpp"

#include <algorithm>
#include <exception>
#include <fstream>
#include <new>
#include <sstream>
#include <tuple>

#include <yaml-cpp/eventhandler.h>
#include <yaml-cpp/yaml.h>

#include "daemon/config/estimator_defaults.hpp"
#include "daemon/config/readers.hpp"
#include "daemon/config/yaml_reader.hpp"

namespace livod::daemon {

std::size_t ConfigResult::error_count() const {
  return static_cast<std::size_t>(
      std::count_if(problems.begin(), problems.end(),
                    [](const ConfigProblem& p) { return p.severity == Severity::error; }));
}

std::size_t ConfigResult::warning_count() const {
  return problems.size() - error_count();
}

namespace {

using config_detail::MapReader;
using config_detail::Position;
using config_detail::ProblemList;
using config_detail::Value;

constexpr std::array<std::string_view, 7> kLogLevels = {"trace", "debug",    "info", "warn",
                                                        "error", "critical", "off"};

void read_logging(MapReader& m, LoggingSection& logging) {
  if (const auto v = m.take("level"); v && !v->node.IsNull()) {
    if (const auto level = config_detail::parse_string(m.problems(), *v)) {
      if (std::find(kLogLevels.begin(), kLogLevels.end(), *level) != kLogLevels.end()) {
        logging.level = *level;
      } else {
        const std::vector<std::string> names(kLogLevels.begin(), kLogLevels.end());
        m.problems().error(ProblemKind::invalid_value, v->path, v->at,
                           "'" + *level + "' is not one of: " + config_detail::join(names) +
                               config_detail::did_you_mean(*level, names));
      }
    }
  }
  m.finish();
}

void read_health(MapReader& m, HealthConfig& health) {
  m.read("period_s", health.period_s, config_detail::closed(0.05, 60.0));
  m.read("stale_after_s", health.stale_after_s, config_detail::left_open(0.0, 60.0));
  m.finish();
}

void read_realtime(MapReader& m, RealtimeConfig& realtime) {
  m.read("capture_priority", realtime.capture_priority, 0, 99);
  m.read("scheduler_priority", realtime.scheduler_priority, 0, 99);
  m.read("capture_cpu", realtime.capture_cpu, -1, 1023);
  m.read("scheduler_cpu", realtime.scheduler_cpu, -1, 1023);
  m.read("lock_memory", realtime.lock_memory);
  m.read("cpu_dma_latency_us", realtime.cpu_dma_latency_us, -1, 1'000'000);
  m.finish();
}

void read_document(ProblemList& problems, const YAML::Node& root,
                   const config_detail::ReadContext& context, LivodConfig& config) {
  MapReader top(problems, root, "",
                config_detail::position_of(root).line > 0 ? config_detail::position_of(root)
                                                          : Position{1, 1});
  if (!top.ok()) return;
  {
    MapReader m = top.map("logging");
    read_logging(m, config.logging);
  }

  Position body_frame_at = top.at();
  if (const auto v = top.require("body_frame", "the IMU whose frame is the body frame")) {
    body_frame_at = v->at;
    if (const auto s = config_detail::parse_string(problems, *v)) config.body_frame = *s;
  }

  std::vector<config_detail::SensorSite> sites;
  Position sensors_at = top.at();
  if (const auto v = top.require("sensors", "a list of sensors")) {
    sensors_at = v->at;
    const auto items = config_detail::sequence_items(problems, *v);
    if (v->node.IsSequence() && items.empty()) {
      problems.error(ProblemKind::invalid_value, v->path, v->at, "the list of sensors is empty");
    }
    config.sensors.resize(items.size());
    sites.resize(items.size());
    for (std::size_t i = 0; i < items.size(); ++i) {
      config_detail::read_sensor(problems, items[i], context, config.sensors[i], sites[i]);
    }
  }
  {
    MapReader m = top.map("estimator");
    config_detail::read_estimator(m, config.estimator, config.estimator_given);
  }
  {
    MapReader m = top.map("outputs");
    config_detail::read_outputs(m, context, config.outputs);
  }
  {
    MapReader m = top.map("health");
    read_health(m, config.health);
  }
  {
    MapReader m = top.map("realtime");
    read_realtime(m, config.realtime);
  }
  top.finish();
  config_detail::check_sensors(problems, config, sites, sensors_at, body_frame_at);
  // The sensors are known: the estimator settings that depend on the LiDAR model.
  apply_estimator_defaults(config);
}

// Counts the documents of a YAML stream (at most two: one is allowed, two is a problem) and
// where they start. YAML::LoadAll is not used: yaml-cpp 0.7 loops forever in it on inputs such as
// a lone "," (jbeder/yaml-cpp#1040, fixed upstream by PR #1319 after 0.7), producing empty
// documents that consume no input; the start marks show that.
class DocumentCounter : public YAML::EventHandler {
 public:
  void OnDocumentStart(const YAML::Mark& mark) override { starts.push_back(mark); }
  void OnDocumentEnd() override {}
  void OnNull(const YAML::Mark&, YAML::anchor_t) override {}
  void OnAlias(const YAML::Mark&, YAML::anchor_t) override {}
  void OnScalar(const YAML::Mark&, const std::string&, YAML::anchor_t,
                const std::string&) override {}
  void OnSequenceStart(const YAML::Mark&, const std::string&, YAML::anchor_t,
                       YAML::EmitterStyle::value) override {}
  void OnSequenceEnd() override {}
  void OnMapStart(const YAML::Mark&, const std::string&, YAML::anchor_t,
                  YAML::EmitterStyle::value) override {}
  void OnMapEnd() override {}

  std::vector<YAML::Mark> starts;
};

Position position_of(const YAML::Mark& mark) {
  return mark.line >= 0 ? Position{mark.line + 1, mark.column + 1} : Position{};
}

void parse_and_read(std::string_view yaml, ProblemList& problems,
                    const config_detail::ReadContext& context, LivodConfig& config) {
  if (yaml.size() > kMaxConfigBytes) {
    problems.error(ProblemKind::syntax, "", {},
                   "the file is larger than " + std::to_string(kMaxConfigBytes) +
                       " bytes; this is not a configuration");
    return;
  }
  const std::string text(yaml);
  YAML::Node root;
  DocumentCounter counter;
  try {
    std::istringstream in(text);
    YAML::Parser parser(in);
    for (int i = 0; i < 2 && parser.HandleNextDocument(counter); ++i) {
    }
    root = YAML::Load(text);
  } catch (const YAML::Exception& e) {
    problems.error(ProblemKind::syntax, "", position_of(e.mark), "YAML syntax: " + e.msg);
    return;
  }
  if (counter.starts.size() > 1) {
    if (counter.starts[1].pos <= counter.starts[0].pos) {
      problems.error(ProblemKind::syntax, "", position_of(counter.starts[0]),
                     "YAML syntax: cannot parse the start of the document (a stray ',', ']' or "
                     "'}'?)");
      return;
    }
    problems.error(ProblemKind::syntax, "", position_of(counter.starts[1]),
                   "the file holds more than one YAML document; livod reads exactly one "
                   "(remove the '---' separators)");
  }
  read_document(problems, root, context, config);
}

}  // namespace

ConfigResult load_config_from_string(std::string_view yaml, std::string source_name,
                                     const std::filesystem::path& base_dir) {
  ConfigResult result;
  result.source = std::move(source_name);
  result.config.base_dir = base_dir;
  ProblemList problems;
  config_detail::ReadContext context{base_dir};
  try {
    parse_and_read(yaml, problems, context, result.config);
  } catch (const std::bad_alloc&) {
    throw;  // out of memory is not a configuration problem
  } catch (const std::exception& e) {
    // Every reader is written not to throw; this is the last line of defence against a library
    // surprise (yaml-cpp throws on unexpected node accesses), reported instead of crashing.
    problems.error(ProblemKind::syntax, "", {},
                   std::string("internal error while reading: ") + e.what());
  }
  result.problems = std::move(problems.items());
  std::stable_sort(result.problems.begin(), result.problems.end(),
                   [](const ConfigProblem& a, const ConfigProblem& b) {
                     return std::tie(a.line, a.column) < std::tie(b.line, b.column);
                   });
  return result;
}

ConfigResult load_config(const std::filesystem::path& path) {
  std::ifstream in(path, std::ios::binary);
  std::error_code ec;
  if (!in || std::filesystem::is_directory(path, ec)) {
    ConfigResult result;
    result.source = path.string();
    result.config.source_file = path;
    result.problems.push_back({Severity::error, ProblemKind::missing_file, "", 0, 0,
                               "cannot read the configuration file"});
    return result;
  }
  // Read at most one byte past the limit: enough to report an oversized file.
  std::string text(kMaxConfigBytes + 1, '\0');
  in.read(text.data(), static_cast<std::streamsize>(text.size()));
  text.resize(static_cast<std::size_t>(in.gcount()));
  auto base_dir = std::filesystem::absolute(path, ec).parent_path();
  auto result = load_config_from_string(text, path.string(), base_dir);
  result.config.source_file = path;
  return result;
}

}  // namespace livod::daemon
