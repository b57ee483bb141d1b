#include "daemon/config/problems.hpp"

#include <algorithm>
#include <cctype>
#include <cstddef>

namespace livod::daemon {

std::string_view to_string(Severity severity) {
  return severity == Severity::error ? "error" : "warning";
}

std::string_view to_string(ProblemKind kind) {
  switch (kind) {
    case ProblemKind::syntax:
      return "syntax";
    case ProblemKind::unknown_key:
      return "unknown_key";
    case ProblemKind::duplicate_key:
      return "duplicate_key";
    case ProblemKind::missing_key:
      return "missing_key";
    case ProblemKind::wrong_type:
      return "wrong_type";
    case ProblemKind::out_of_range:
      return "out_of_range";
    case ProblemKind::invalid_value:
      return "invalid_value";
    case ProblemKind::duplicate_name:
      return "duplicate_name";
    case ProblemKind::duplicate_port:
      return "duplicate_port";
    case ProblemKind::missing_extrinsic:
      return "missing_extrinsic";
    case ProblemKind::missing_file:
      return "missing_file";
    case ProblemKind::inconsistent:
      return "inconsistent";
    case ProblemKind::not_implemented:
      return "not implemented";
  }
  return "unknown";
}

std::string format_problem(std::string_view source, const ConfigProblem& problem) {
  std::string out(source);
  if (problem.line > 0) {
    out += ':' + std::to_string(problem.line) + ':' + std::to_string(problem.column);
  }
  out += ": ";
  out += to_string(problem.severity);
  out += ": ";
  if (!problem.path.empty()) {
    out += problem.path;
    out += ": ";
  }
  out += problem.message;
  return out;
}

namespace {

// Keys and enum values are short; longer words are not typos of them and would only cost time.
constexpr std::size_t kMaxSuggestionLength = 64;

char lower(char c) {
  return static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
}

// Optimal string alignment distance (Levenshtein plus adjacent transpositions), case-insensitive:
// "prot" -> "port" is one edit, as a person would count it.
std::size_t edit_distance(std::string_view a, std::string_view b) {
  const std::size_t n = a.size();
  const std::size_t m = b.size();
  std::vector<std::size_t> prev2(m + 1), prev(m + 1), cur(m + 1);
  for (std::size_t j = 0; j <= m; ++j) prev[j] = j;
  for (std::size_t i = 1; i <= n; ++i) {
    cur[0] = i;
    for (std::size_t j = 1; j <= m; ++j) {
      const std::size_t cost = lower(a[i - 1]) == lower(b[j - 1]) ? 0 : 1;
      cur[j] = std::min({prev[j] + 1, cur[j - 1] + 1, prev[j - 1] + cost});
      if (i > 1 && j > 1 && lower(a[i - 1]) == lower(b[j - 2]) &&
          lower(a[i - 2]) == lower(b[j - 1])) {
        cur[j] = std::min(cur[j], prev2[j - 2] + 1);
      }
    }
    prev2.swap(prev);
    prev.swap(cur);
  }
  return prev[m];
}

}  // namespace

std::string closest_match(std::string_view word, const std::vector<std::string>& candidates) {
  if (word.empty() || word.size() > kMaxSuggestionLength) return {};
  std::string best;
  std::size_t best_distance = 0;
  for (const auto& candidate : candidates) {
    // A third of the candidate's length (at least one edit) separates typos from other words.
    const std::size_t allowed = std::max<std::size_t>(1, candidate.size() / 3);
    const std::size_t distance = edit_distance(word, candidate);
    if (distance <= allowed && (best.empty() || distance < best_distance)) {
      best = candidate;
      best_distance = distance;
    }
  }
  return best;
}

}  // namespace livod::daemon
