#pragma once
// Shared by the live source tests (live_camera_source_test.cpp,
// live_device_sources_threads_test.cpp): configuration snippets, a loader that fails the test on
// any error, and a drain loop that feeds a source like the scheduler does.

#include <gtest/gtest.h>

#include <chrono>
#include <cstdint>
#include <string>
#include <thread>
#include <vector>

#include "daemon/config/load_config.hpp"
#include "daemon/runtime/source.hpp"

namespace livod::daemon::runtime::test_support {

inline const std::string kLidar =
    R"(  - {name: vlp, driver: velodyne, model: VLP-16, source: {udp: {}},
     extrinsic: {translation: [0, 0, 0], rotation: {rpy_deg: [0, 0, 0]}}}
)";
inline const std::string kExtrinsic =
    "    extrinsic: {translation: [0, 0, 0], rotation: {rpy_deg: [0, 0, 0]}}\n";

// `livod run` takes these configurations: check-config finds no error in them.
inline LivodConfig load_runnable(const std::string& yaml) {
  auto r = load_config_from_string(yaml, "test.yaml");
  for (const auto& p : r.problems) {
    EXPECT_NE(p.severity, Severity::error) << format_problem(r.source, p);
  }
  return r.config;
}

// Drains a source like the scheduler does: peek, deliver, until `done` or 10 s.
template <class Done>
bool drain(MeasurementSource& source, const drivers::DecoderSinks& sinks, Done&& done,
           std::vector<std::int64_t>* peeked = nullptr) {
  const auto deadline = std::chrono::steady_clock::now() + std::chrono::seconds(10);
  while (!done() && std::chrono::steady_clock::now() < deadline) {
    if (const auto t = source.peek_time()) {
      if (peeked != nullptr) peeked->push_back(*t);
      source.deliver(sinks);
    } else {
      std::this_thread::sleep_for(std::chrono::milliseconds(2));
    }
  }
  return done();
}

}  // namespace livod::daemon::runtime::test_support
