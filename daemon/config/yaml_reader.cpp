#include "daemon/config/yaml_reader.hpp"

#include <algorithm>
#include <cctype>
#include <charconv>
#include <cmath>
#include <sstream>
#include <system_error>

namespace livod::daemon::config_detail {

Position position_of(const YAML::Node& node) {
  const YAML::Mark mark = node.Mark();
  if (mark.line < 0 || mark.column < 0) return {};
  return {mark.line + 1, mark.column + 1};
}

void ProblemList::error(ProblemKind kind, std::string path, Position at, std::string message) {
  items_.push_back(
      {Severity::error, kind, std::move(path), at.line, at.column, std::move(message)});
}

void ProblemList::warning(ProblemKind kind, std::string path, Position at, std::string message) {
  items_.push_back(
      {Severity::warning, kind, std::move(path), at.line, at.column, std::move(message)});
}

bool Range::contains(double v) const {
  if (!std::isfinite(v)) return false;
  const bool above = min_inclusive ? v >= min : v > min;
  const bool below = max_inclusive ? v <= max : v < max;
  return above && below;
}

std::string Range::describe() const {
  return std::string(min_inclusive ? "[" : "(") + format_number(min) + ", " + format_number(max) +
         (max_inclusive ? "]" : ")");
}

std::string format_number(double v) {
  std::ostringstream out;
  out.precision(10);
  out << v;
  return out.str();
}

std::string describe_node(const YAML::Node& node) {
  // Long scalars (fuzzed input, pasted blobs) are cut so that a message stays one readable line.
  constexpr std::size_t kMaxQuoted = 40;
  switch (node.Type()) {
    case YAML::NodeType::Scalar: {
      const std::string& s = node.Scalar();
      if (s.size() <= kMaxQuoted) return "'" + s + "'";
      return "'" + s.substr(0, kMaxQuoted) + "...'";
    }
    case YAML::NodeType::Map:
      return "a mapping";
    case YAML::NodeType::Sequence:
      return "a list";
    default:
      return "nothing";
  }
}

std::string join(const std::vector<std::string>& words) {
  std::string out;
  for (const auto& w : words) {
    if (!out.empty()) out += ", ";
    out += w;
  }
  return out;
}

std::string did_you_mean(std::string_view word, const std::vector<std::string>& candidates) {
  const std::string match = closest_match(word, candidates);
  if (match.empty()) return {};
  return " (did you mean '" + match + "'?)";
}

namespace {

std::optional<double> to_double(std::string_view s) {
  if (!s.empty() && s.front() == '+') s.remove_prefix(1);
  if (s.empty()) return std::nullopt;
  double v = 0.0;
  const auto [end, ec] = std::from_chars(s.data(), s.data() + s.size(), v);
  if (ec != std::errc() || end != s.data() + s.size()) return std::nullopt;
  return v;
}

std::optional<long long> to_integer(std::string_view s) {
  bool negative = false;
  if (!s.empty() && (s.front() == '+' || s.front() == '-')) {
    negative = s.front() == '-';
    s.remove_prefix(1);
  }
  int base = 10;
  if (s.size() > 2 && s[0] == '0' && (s[1] == 'x' || s[1] == 'X')) {
    base = 16;  // CAN identifiers are written in hex
    s.remove_prefix(2);
  }
  if (s.empty()) return std::nullopt;
  long long v = 0;
  const auto [end, ec] = std::from_chars(s.data(), s.data() + s.size(), v, base);
  if (ec != std::errc() || end != s.data() + s.size()) return std::nullopt;
  return negative ? -v : v;
}

std::string lower(std::string_view s) {
  std::string out(s);
  for (auto& c : out) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
  return out;
}

bool expect_scalar(ProblemList& problems, const Value& v, std::string_view expected) {
  if (v.node.IsScalar()) return true;
  problems.error(ProblemKind::wrong_type, v.path, v.at,
                 "expected " + std::string(expected) + ", got " + describe_node(v.node));
  return false;
}

}  // namespace

std::optional<bool> parse_bool(ProblemList& problems, const Value& v) {
  if (!expect_scalar(problems, v, "true or false")) return std::nullopt;
  const std::string s = lower(v.node.Scalar());
  if (s == "true" || s == "yes" || s == "on") return true;
  if (s == "false" || s == "no" || s == "off") return false;
  problems.error(ProblemKind::wrong_type, v.path, v.at,
                 "expected true or false, got " + describe_node(v.node));
  return std::nullopt;
}

std::optional<double> parse_double(ProblemList& problems, const Value& v, const Range& range) {
  if (!expect_scalar(problems, v, "a number")) return std::nullopt;
  const auto value = to_double(v.node.Scalar());
  if (!value) {
    problems.error(ProblemKind::wrong_type, v.path, v.at,
                   "expected a number, got " + describe_node(v.node));
    return std::nullopt;
  }
  if (!std::isfinite(*value)) {
    problems.error(ProblemKind::out_of_range, v.path, v.at, "must be a finite number");
    return std::nullopt;
  }
  if (!range.contains(*value)) {
    problems.error(ProblemKind::out_of_range, v.path, v.at,
                   "must be in " + range.describe() + ", got " + format_number(*value));
    return std::nullopt;
  }
  return value;
}

std::optional<long long> parse_integer(ProblemList& problems, const Value& v, long long lo,
                                       long long hi) {
  if (!expect_scalar(problems, v, "an integer")) return std::nullopt;
  const auto value = to_integer(v.node.Scalar());
  if (!value) {
    problems.error(ProblemKind::wrong_type, v.path, v.at,
                   "expected an integer, got " + describe_node(v.node));
    return std::nullopt;
  }
  if (*value < lo || *value > hi) {
    problems.error(ProblemKind::out_of_range, v.path, v.at,
                   "must be in [" + std::to_string(lo) + ", " + std::to_string(hi) + "], got " +
                       std::to_string(*value));
    return std::nullopt;
  }
  return value;
}

std::optional<std::string> parse_string(ProblemList& problems, const Value& v, bool allow_null) {
  if (v.node.IsNull()) {
    if (!allow_null) {
      problems.error(ProblemKind::wrong_type, v.path, v.at, "expected a value, got nothing");
    }
    return std::nullopt;
  }
  if (!expect_scalar(problems, v, "a string")) return std::nullopt;
  return v.node.Scalar();
}

std::vector<Value> sequence_items(ProblemList& problems, const Value& v) {
  std::vector<Value> items;
  if (!v.node.IsSequence()) {
    problems.error(ProblemKind::wrong_type, v.path, v.at,
                   "expected a list, got " + describe_node(v.node));
    return items;
  }
  std::size_t i = 0;
  for (const auto& item : v.node) {
    Position at = position_of(item);
    if (at.line == 0 || item.IsNull()) at = v.at;
    items.push_back({item, v.path + "[" + std::to_string(i) + "]", at});
    ++i;
  }
  return items;
}

std::optional<std::vector<double>> parse_numbers(ProblemList& problems, const Value& v,
                                                 std::size_t min_count, std::size_t max_count,
                                                 const Range& range) {
  if (!v.node.IsSequence()) {
    problems.error(ProblemKind::wrong_type, v.path, v.at,
                   "expected a list of numbers, got " + describe_node(v.node));
    return std::nullopt;
  }
  const std::size_t n = v.node.size();
  if (n < min_count || n > max_count) {
    const std::string wanted = min_count == max_count
                                   ? std::to_string(min_count)
                                   : std::to_string(min_count) + " to " + std::to_string(max_count);
    problems.error(ProblemKind::invalid_value, v.path, v.at,
                   "expected " + wanted + " numbers, got " + std::to_string(n));
    return std::nullopt;
  }
  std::vector<double> values;
  bool ok = true;
  for (const auto& item : sequence_items(problems, v)) {
    const auto value = parse_double(problems, item, range);
    ok = ok && value.has_value();
    values.push_back(value.value_or(0.0));
  }
  if (!ok) return std::nullopt;
  return values;
}

MapReader::MapReader(ProblemList& problems, const YAML::Node& node, std::string path, Position at,
                     bool allow_null)
    : problems_(problems), path_(std::move(path)), at_(at) {
  if (node.IsNull()) {
    ok_ = allow_null;
    if (!allow_null) {
      problems_.error(ProblemKind::wrong_type, path_, at_, "expected a mapping, got nothing");
    }
    return;
  }
  if (!node.IsMap()) {
    problems_.error(ProblemKind::wrong_type, path_, at_,
                    "expected a mapping, got " + describe_node(node));
    return;
  }
  ok_ = true;
  // Range-for binds each key/value pair by value; `it->first` would refer into a temporary.
  for (const auto& pair : node) {
    const YAML::Node& key = pair.first;
    const Position key_at = position_of(key).line > 0 ? position_of(key) : at_;
    if (!key.IsScalar()) {
      problems_.error(ProblemKind::wrong_type, path_, key_at,
                      "keys must be plain names, got " + describe_node(key));
      continue;
    }
    const std::string& name = key.Scalar();
    if (const Entry* first = find(name)) {
      problems_.error(ProblemKind::duplicate_key, child_path(name), key_at,
                      "key '" + name + "' appears twice (first at line " +
                          std::to_string(first->key_at.line) + "); the first one is used");
      continue;
    }
    entries_.push_back({name, key_at, pair.second});
  }
}

MapReader::MapReader(ProblemList& problems, std::string path, Position at)
    : problems_(problems), path_(std::move(path)), at_(at) {}

std::string MapReader::child_path(std::string_view key) const {
  if (path_.empty()) return std::string(key);
  return path_ + "." + std::string(key);
}

const MapReader::Entry* MapReader::find(std::string_view key) const {
  for (const auto& e : entries_) {
    if (e.key == key) return &e;
  }
  return nullptr;
}

void MapReader::declare(std::string_view key) {
  if (std::find(declared_.begin(), declared_.end(), key) == declared_.end()) {
    declared_.emplace_back(key);
  }
}

std::optional<Value> MapReader::take(std::string_view key) {
  declare(key);
  const Entry* e = find(key);
  if (e == nullptr) return std::nullopt;
  Position at = position_of(e->value);
  // yaml-cpp places an empty value at the start of the next token; the key is where it is.
  if (e->value.IsNull() || at.line == 0) at = e->key_at;
  return Value{e->value, child_path(key), at};
}

bool MapReader::has(std::string_view key) {
  const auto v = take(key);
  return v && !v->node.IsNull();
}

std::optional<Value> MapReader::require(std::string_view key, std::string_view what) {
  auto v = take(key);
  if (v && !v->node.IsNull()) return v;
  if (!ok_) return std::nullopt;
  std::string message = "missing required key '" + std::string(key) + "'";
  if (!what.empty()) message += " (" + std::string(what) + ")";
  problems_.error(ProblemKind::missing_key, child_path(key), v ? v->at : at_, message);
  return std::nullopt;
}

Position MapReader::key_at(std::string_view key) const {
  const Entry* e = find(key);
  return e != nullptr ? e->key_at : at_;
}

std::vector<std::string> MapReader::present_keys() const {
  std::vector<std::string> keys;
  for (const auto& e : entries_) keys.push_back(e.key);
  return keys;
}

bool MapReader::read(std::string_view key, bool& out) {
  const auto v = take(key);
  if (!v) return false;
  const auto parsed = parse_bool(problems_, *v);
  if (parsed) out = *parsed;
  return parsed.has_value();
}

bool MapReader::read(std::string_view key, double& out, const Range& range) {
  const auto v = take(key);
  if (!v) return false;
  const auto parsed = parse_double(problems_, *v, range);
  if (parsed) out = *parsed;
  return parsed.has_value();
}

bool MapReader::read(std::string_view key, int& out, long long lo, long long hi) {
  const auto v = take(key);
  if (!v) return false;
  const auto parsed = parse_integer(problems_, *v, lo, hi);
  if (parsed) out = static_cast<int>(*parsed);
  return parsed.has_value();
}

bool MapReader::read(std::string_view key, std::string& out) {
  const auto v = take(key);
  if (!v) return false;
  const auto parsed = parse_string(problems_, *v, true);
  if (parsed) out = *parsed;
  return parsed.has_value();
}

bool MapReader::read_optional(std::string_view key, std::optional<double>& out,
                              const Range& range) {
  const auto v = take(key);
  if (!v || v->node.IsNull()) return false;
  const auto parsed = parse_double(problems_, *v, range);
  if (parsed) out = *parsed;
  return parsed.has_value();
}

MapReader MapReader::map(std::string_view key) {
  const auto v = take(key);
  if (!v || !ok_) return MapReader(problems_, child_path(key), key_at(key));
  return MapReader(problems_, v->node, v->path, v->at);
}

void MapReader::finish() {
  for (const auto& e : entries_) {
    if (std::find(declared_.begin(), declared_.end(), e.key) != declared_.end()) continue;
    problems_.error(ProblemKind::unknown_key, child_path(e.key), e.key_at,
                    "unknown key '" + e.key + "'" + did_you_mean(e.key, declared_));
  }
}

}  // namespace livod::daemon::config_detail
