#include "io/rosbag/ros_md5.hpp"

#include <array>
#include <map>
#include <set>
#include <vector>

#include "core/error.hpp"
#include "core/text.hpp"
#include "io/rosbag/md5.hpp"

namespace livod::io::rosbag {
namespace {

constexpr std::size_t kSeparatorLength = 80;
constexpr std::string_view kMsgPrefix = "MSG:";
// Nesting deeper than this can only be a cycle or garbage.
constexpr int kMaxDepth = 32;

constexpr std::array<std::string_view, 16> kBuiltinTypes = {
    "bool",   "byte",  "char",   "int8",    "uint8",   "int16",  "uint16", "int32",
    "uint32", "int64", "uint64", "float32", "float64", "string", "time",   "duration"};

std::vector<std::string_view> split_whitespace(std::string_view s) {
  std::vector<std::string_view> out;
  std::size_t i = 0;
  while (i < s.size()) {
    while (i < s.size() && (s[i] == ' ' || s[i] == '\t')) ++i;
    std::size_t j = i;
    while (j < s.size() && s[j] != ' ' && s[j] != '\t') ++j;
    if (j > i) out.push_back(s.substr(i, j - i));
    i = j;
  }
  return out;
}

bool is_separator(std::string_view line) {
  line = trim_whitespace(line);
  return line.size() == kSeparatorLength && line.find_first_not_of('=') == std::string_view::npos;
}

std::string_view bare_type(std::string_view type) {
  const auto bracket = type.find('[');
  return bracket == std::string_view::npos ? type : type.substr(0, bracket);
}

bool is_builtin(std::string_view bare) {
  for (auto b : kBuiltinTypes) {
    if (b == bare) return true;
  }
  return false;
}

std::string_view package_of(std::string_view full_type) {
  const auto slash = full_type.find('/');
  return slash == std::string_view::npos ? std::string_view{} : full_type.substr(0, slash);
}

// Full name of a non-builtin field type used inside a message of package `package`.
std::string resolve_type(std::string_view bare, std::string_view package) {
  if (bare == "Header") return "std_msgs/Header";
  if (bare.find('/') != std::string_view::npos) return std::string(bare);
  return std::string(package) + "/" + std::string(bare);
}

class Md5Computer {
 public:
  Md5Computer(std::string_view top_type, std::string_view text) {
    std::string current(top_type);
    std::vector<std::string_view> lines;
    std::size_t pos = 0;
    bool expect_msg_line = false;
    while (pos <= text.size()) {
      auto end = text.find('\n', pos);
      if (end == std::string_view::npos) end = text.size();
      const std::string_view line = text.substr(pos, end - pos);
      pos = end + 1;
      if (is_separator(line)) {
        sections_[current] = std::move(lines);
        lines.clear();
        current.clear();
        expect_msg_line = true;
        continue;
      }
      if (expect_msg_line) {
        const auto t = trim_whitespace(line);
        if (t.empty()) continue;
        if (t.substr(0, kMsgPrefix.size()) != kMsgPrefix) {
          throw Error("message definition of " + std::string(top_type) +
                      ": expected 'MSG: <type>' after a separator, got '" + std::string(t) + "'");
        }
        current = std::string(trim_whitespace(t.substr(kMsgPrefix.size())));
        expect_msg_line = false;
        continue;
      }
      lines.push_back(line);
    }
    if (expect_msg_line) {
      throw Error("message definition of " + std::string(top_type) + ": separator without MSG");
    }
    sections_[current] = std::move(lines);
  }

  std::string md5_of(const std::string& type, int depth) {
    if (auto it = memo_.find(type); it != memo_.end()) return it->second;
    if (depth > kMaxDepth || in_progress_.contains(type)) {
      throw Error("message definition: recursive or too deeply nested type " + type);
    }
    auto sec = sections_.find(type);
    if (sec == sections_.end()) {
      throw Error("message definition does not define " + type);
    }
    in_progress_.insert(type);
    const std::string_view package = package_of(type);
    std::string constants;
    std::string fields;
    for (std::string_view line : sec->second) {
      add_line(type, package, line, depth, constants, fields);
    }
    std::string md5_text = constants + fields;
    if (!md5_text.empty()) md5_text.pop_back();  // genmsg strips the final newline
    in_progress_.erase(type);
    return memo_[type] = md5_hex(md5_text);
  }

 private:
  void add_line(const std::string& type, std::string_view package, std::string_view line, int depth,
                std::string& constants, std::string& fields) {
    const std::string_view clean = trim_whitespace(line.substr(0, line.find('#')));
    if (clean.empty()) return;
    const auto tokens = split_whitespace(clean);
    const std::string_view field_type = tokens[0];
    const auto eq = clean.find('=');
    if (eq != std::string_view::npos) {
      std::string name;
      std::string value;
      if (field_type == "string") {
        // A string constant is everything after '=' on the original line, '#' included.
        const auto raw_eq = line.find('=');
        const auto type_end = line.find(field_type) + field_type.size();
        name = std::string(trim_whitespace(line.substr(type_end, raw_eq - type_end)));
        value = std::string(trim_whitespace(line.substr(raw_eq + 1)));
      } else {
        const auto type_end = clean.find(field_type) + field_type.size();
        name = std::string(trim_whitespace(clean.substr(type_end, eq - type_end)));
        value = std::string(trim_whitespace(clean.substr(eq + 1)));
      }
      if (name.empty()) throw Error("message definition of " + type + ": bad constant line");
      constants += std::string(field_type) + " " + name + "=" + value + "\n";
      return;
    }
    if (tokens.size() != 2) {
      throw Error("message definition of " + type + ": bad field line '" + std::string(clean) +
                  "'");
    }
    const std::string_view bare = bare_type(field_type);
    if (is_builtin(bare)) {
      fields += std::string(field_type) + " " + std::string(tokens[1]) + "\n";
    } else {
      fields +=
          md5_of(resolve_type(bare, package), depth + 1) + " " + std::string(tokens[1]) + "\n";
    }
  }

  std::map<std::string, std::vector<std::string_view>> sections_;
  std::map<std::string, std::string> memo_;
  std::set<std::string> in_progress_;
};

}  // namespace

std::string compute_ros_md5sum(std::string_view type, std::string_view full_definition) {
  Md5Computer computer(type, full_definition);
  return computer.md5_of(std::string(type), 0);
}

}  // namespace livod::io::rosbag
