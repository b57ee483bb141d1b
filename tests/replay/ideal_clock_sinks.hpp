#pragma once
// Decoder sinks that feed a LIO pipeline with ideal clocks (mapped time = sensor time), for tests
// that stream the simulator through a decoder into the estimator without files. Clock mapping has
// its own tests (replay_clock_test.cpp, core/tests/clock_domain_test.cpp).

#include "drivers/lidar_decoder.hpp"
#include "estimator/pipeline.hpp"

namespace livod::test {

inline drivers::DecoderSinks ideal_clock_sinks(estimator::LioPipeline& pipeline) {
  drivers::DecoderSinks sinks;
  sinks.on_scan = [&pipeline](const LidarScan& s) {
    LidarScan copy = s;
    copy.start.mapped = MappedTime(s.start.sensor.ns);
    pipeline.add_scan(std::move(copy));
  };
  sinks.on_imu = [&pipeline](const ImuSample& m) {
    ImuSample copy = m;
    copy.stamp.mapped = MappedTime(m.stamp.sensor.ns);
    pipeline.add_imu(copy);
  };
  return sinks;
}

}  // namespace livod::test
