#pragma once
// Helpers shared by the configuration tests: a small valid configuration to start from and
// readable dumps of the problems a load produced.

#include <gtest/gtest.h>

#include <algorithm>
#include <string>
#include <string_view>

#include "daemon/config/load_config.hpp"

namespace livod::daemon::test {

// A valid configuration: a VLP-16 and an Xsens serial IMU as the body frame.
inline std::string minimal_config() {
  return R"(body_frame: imu
sensors:
  - name: lidar
    driver: velodyne
    model: VLP-16
    source: {udp: {}}
    extrinsic:
      translation: [0.1, 0.0, 0.2]
      rotation: {rpy_deg: [0, 0, 0]}
  - name: imu
    driver: serial_imu
    source: {device: {path: /dev/ttyUSB0}}
    serial: {protocol: xsens_mtdata2}
)";
}

inline std::string dump(const ConfigResult& result) {
  std::string out;
  for (const auto& p : result.problems) {
    out += format_problem(result.source, p) + " [" + std::string(to_string(p.kind)) + "]\n";
  }
  return out.empty() ? std::string("(no problems)\n") : out;
}

inline const ConfigProblem* find_problem(const ConfigResult& result, ProblemKind kind,
                                         std::string_view path) {
  const auto it =
      std::find_if(result.problems.begin(), result.problems.end(),
                   [&](const ConfigProblem& p) { return p.kind == kind && p.path == path; });
  return it == result.problems.end() ? nullptr : &*it;
}

// Loads a configuration for the schema tests, without the "not implemented" errors: these tests
// check reading and validation, and some use combinations livod refuses to run (a second IMU
// besides the body IMU, two cameras, the visual update with two LiDARs). What is refused is
// checked by ConfigImplemented (problems_test.cpp), which loads with load_config_from_string.
inline ConfigResult without_not_implemented(ConfigResult r) {
  std::erase_if(r.problems,
                [](const ConfigProblem& p) { return p.kind == ProblemKind::not_implemented; });
  return r;
}
inline ConfigResult load(const std::string& yaml) {
  return without_not_implemented(load_config_from_string(yaml, "test.yaml"));
}

}  // namespace livod::daemon::test
