#pragma once
// Internal to livod_daemon_config (it includes yaml-cpp, which the library links privately):
// typed, never-throwing reads of YAML nodes that report every problem with its YAML path and
// position, and a mapping reader that knows which keys were expected so that the rest can be
// reported as unknown, with a "did you mean" for near misses.

#include <yaml-cpp/yaml.h>

#include <cstdint>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "daemon/config/config.hpp"
#include "daemon/config/problems.hpp"

namespace livod::daemon::config_detail {

struct Position {
  int line = 0;  // 1-based; 0 = unknown
  int column = 0;
};

Position position_of(const YAML::Node& node);

class ProblemList {
 public:
  void error(ProblemKind kind, std::string path, Position at, std::string message);
  void warning(ProblemKind kind, std::string path, Position at, std::string message);
  [[nodiscard]] std::vector<ConfigProblem>& items() { return items_; }

 private:
  std::vector<ConfigProblem> items_;
};

// A closed or half-open interval of allowed numbers, described in messages as e.g. "(0, 1]".
struct Range {
  double min = 0.0;
  double max = 0.0;
  bool min_inclusive = true;
  bool max_inclusive = true;

  [[nodiscard]] bool contains(double v) const;
  [[nodiscard]] std::string describe() const;
};

inline Range closed(double lo, double hi) {
  return {lo, hi, true, true};
}
inline Range left_open(double lo, double hi) {
  return {lo, hi, false, true};
}
inline Range right_open(double lo, double hi) {
  return {lo, hi, true, false};
}

std::string format_number(double v);
// "'text'", "a mapping", "a list" or "null": what was found instead of the expected type.
std::string describe_node(const YAML::Node& node);
std::string join(const std::vector<std::string>& words);
// " (did you mean 'x'?)" or "".
std::string did_you_mean(std::string_view word, const std::vector<std::string>& candidates);

// One YAML value with its path and position (the key's position when the value is empty).
struct Value {
  YAML::Node node;
  std::string path;
  Position at;
};

std::optional<bool> parse_bool(ProblemList& problems, const Value& v);
std::optional<double> parse_double(ProblemList& problems, const Value& v, const Range& range);
std::optional<long long> parse_integer(ProblemList& problems, const Value& v, long long lo,
                                       long long hi);
// A scalar as text; nullopt (and a problem) for mappings and lists, nullopt without a problem for
// null when allow_null.
std::optional<std::string> parse_string(ProblemList& problems, const Value& v,
                                        bool allow_null = false);
// A list of exactly `count` numbers (count 0 = any length between min_count and max_count).
std::optional<std::vector<double>> parse_numbers(ProblemList& problems, const Value& v,
                                                 std::size_t min_count, std::size_t max_count,
                                                 const Range& range);
std::vector<Value> sequence_items(ProblemList& problems, const Value& v);

template <class E>
std::optional<E> parse_enum(ProblemList& problems, const Value& v) {
  const auto text = parse_string(problems, v);
  if (!text) return std::nullopt;
  if (const auto value = daemon::parse_enum<E>(*text)) return value;
  std::vector<std::string> names;
  for (const auto& entry : enum_entries<E>()) names.emplace_back(entry.name);
  problems.error(ProblemKind::invalid_value, v.path, v.at,
                 "'" + *text + "' is not one of: " + join(names) + did_you_mean(*text, names));
  return std::nullopt;
}

// Reads one YAML mapping. Every key the schema knows is declared by a read/take call, so that
// finish() can report the remaining keys as unknown.
class MapReader {
 public:
  // A node that is not a mapping is reported once (unless it is null and allow_null) and the
  // reader then yields nothing.
  MapReader(ProblemList& problems, const YAML::Node& node, std::string path, Position at,
            bool allow_null = true);
  // A reader for an absent section: yields nothing, reports nothing.
  MapReader(ProblemList& problems, std::string path, Position at);

  [[nodiscard]] bool ok() const { return ok_; }
  [[nodiscard]] const std::string& path() const { return path_; }
  [[nodiscard]] Position at() const { return at_; }
  [[nodiscard]] std::string child_path(std::string_view key) const;
  [[nodiscard]] ProblemList& problems() { return problems_; }

  // Declares `key` and returns its value when present (a null value counts as present).
  std::optional<Value> take(std::string_view key);
  // Declares `key`; true when present with a non-null value.
  bool has(std::string_view key);
  // Declares `key`; reports missing_key when absent or null.
  std::optional<Value> require(std::string_view key, std::string_view what = {});
  // Position of a key (for problems about the key itself); at() when absent.
  [[nodiscard]] Position key_at(std::string_view key) const;
  // Keys present in the file, in file order.
  [[nodiscard]] std::vector<std::string> present_keys() const;

  bool read(std::string_view key, bool& out);
  bool read(std::string_view key, double& out, const Range& range);
  bool read(std::string_view key, int& out, long long lo, long long hi);
  bool read(std::string_view key, std::string& out);  // null leaves `out` unchanged
  bool read_optional(std::string_view key, std::optional<double>& out, const Range& range);
  template <class E>
  bool read_enum(std::string_view key, E& out) {
    const auto v = take(key);
    if (!v || v->node.IsNull()) return false;
    const auto parsed = config_detail::parse_enum<E>(problems_, *v);
    if (parsed) out = *parsed;
    return parsed.has_value();
  }

  // A nested mapping; an absent or null key gives a reader that yields nothing.
  MapReader map(std::string_view key);

  // Reports every present key that no read/take/has/require declared.
  void finish();

 private:
  struct Entry {
    std::string key;
    Position key_at;
    YAML::Node value;
  };
  const Entry* find(std::string_view key) const;
  void declare(std::string_view key);

  ProblemList& problems_;
  std::string path_;
  Position at_;
  bool ok_ = false;
  std::vector<Entry> entries_;
  std::vector<std::string> declared_;
};

}  // namespace livod::daemon::config_detail
