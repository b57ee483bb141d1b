#pragma once
// Problems found while loading a configuration file. Loading never throws on bad user input:
// every problem (YAML syntax, unknown key, wrong type, range, cross-sensor conflict) becomes one
// ConfigProblem with the YAML path of the offending value and its line:column, so that one run of
// `livod check-config` lists everything that needs fixing.

#include <string>
#include <string_view>
#include <vector>

namespace livod::daemon {

enum class Severity { warning, error };

// What kind of mistake it is; tests and tools match on this, people read the message.
enum class ProblemKind {
  syntax,             // not valid YAML, too large, more than one document
  unknown_key,        // a key livod does not know (with a "did you mean" when close)
  duplicate_key,      // the same key twice in one mapping
  missing_key,        // a required key is absent
  wrong_type,         // e.g. a string where a number is expected
  out_of_range,       // a number outside its allowed interval
  invalid_value,      // a string that is not one of the allowed values, bad name/address
  duplicate_name,     // two sensors with the same name
  duplicate_port,     // two streams receiving on the same local UDP port
  missing_extrinsic,  // a sensor other than the body IMU without extrinsic
  missing_file,       // a referenced file or folder does not exist
  inconsistent,       // values that are fine alone but contradict each other
  not_implemented,    // valid, but livod cannot do it yet: an error, never silently ignored
};

struct ConfigProblem {
  Severity severity = Severity::error;
  ProblemKind kind = ProblemKind::syntax;
  std::string path;  // YAML path, e.g. "sensors[1].source.udp.ports.lidar"; empty = whole file
  int line = 0;      // 1-based; 0 when the problem has no position (e.g. unreadable file)
  int column = 0;    // 1-based
  std::string message;
};

std::string_view to_string(Severity severity);
std::string_view to_string(ProblemKind kind);

// "FILE:LINE:COL: error: path: message" (the position and the path are left out when unknown).
std::string format_problem(std::string_view source, const ConfigProblem& problem);

// The candidate closest to `word` (optimal string alignment distance, case-insensitive), or an
// empty string when none is close enough to be a plausible typo.
std::string closest_match(std::string_view word, const std::vector<std::string>& candidates);

}  // namespace livod::daemon
