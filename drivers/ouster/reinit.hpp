#pragma once
// Ouster re-initialisation on the live path. An Ouster sensor that restarts (power cycle, config
// change, firmware watchdog) sends lidar packets with a new init_id; the OusterDecoder notices,
// resets its frame tracking, counts it and reports that its metadata is out of date. This module
// re-reads the metadata over HTTP (GET /api/v1/sensor/metadata) on a worker thread and installs a
// decoder built from it in the StreamConsumer, without restarting sockets, rings or threads.
//
//   OusterMetadataFetcher: the worker thread; blocking HTTP with a timeout, off the scheduler.
//   OusterReinitHandler:   consumer-thread glue; decides when to ask and swaps the decoder.
//
// A refetch is asked for when the decoder reports metadata_init_id_mismatch() (non-LEGACY
// profiles carry init_id) or when a stream came back from STALE (LEGACY profiles carry no
// init_id; a sensor that was silent may have restarted with another configuration).

#include <chrono>
#include <condition_variable>
#include <cstdint>
#include <functional>
#include <mutex>
#include <optional>
#include <stop_token>
#include <string>
#include <thread>

#include "core/time.hpp"
#include "drivers/capture/health.hpp"
#include "drivers/capture/stream_consumer.hpp"
#include "drivers/ouster/metadata.hpp"
#include "drivers/ouster/ouster_decoder.hpp"

namespace livod::drivers::ouster {

struct OusterMetadataFetcherConfig {
  std::string host;  // the sensor's address
  std::uint16_t port = 80;
  std::chrono::milliseconds timeout{2000};  // bounds one fetch (and how long stop() may wait)
  // Called on the fetcher thread with the JSON text of every fetch that parsed (the recorder
  // keeps it beside the recording). May be empty; must not block for long.
  std::function<void(const std::string& json)> on_fetched;
};

struct OusterFetchCounters {
  std::uint64_t requests = 0;  // request() calls that started a fetch
  std::uint64_t successes = 0;
  std::uint64_t failures = 0;
};

class OusterMetadataFetcher {
 public:
  explicit OusterMetadataFetcher(OusterMetadataFetcherConfig config);
  // Stops and joins (waits for a fetch in progress, at most config.timeout).
  ~OusterMetadataFetcher();
  OusterMetadataFetcher(const OusterMetadataFetcher&) = delete;
  OusterMetadataFetcher& operator=(const OusterMetadataFetcher&) = delete;

  // Any thread, never blocks on the network: asks for one fetch (coalesced with a pending one).
  void request();
  // Any thread: the metadata of the latest successful fetch not yet taken.
  [[nodiscard]] std::optional<ouster::SensorMetadata> take();
  [[nodiscard]] bool busy() const;  // a fetch is requested or in progress
  [[nodiscard]] OusterFetchCounters counters() const;
  [[nodiscard]] std::string last_error() const;

  void stop();

 private:
  void run(const std::stop_token& stop);

  OusterMetadataFetcherConfig config_;
  mutable std::mutex mutex_;
  std::condition_variable_any wake_;
  bool requested_ = false;  // guarded by mutex_ (like everything below)
  bool fetching_ = false;
  std::optional<ouster::SensorMetadata> ready_;
  OusterFetchCounters counters_;
  std::string last_error_;
  std::jthread thread_;  // last
};

class OusterReinitHandler {
 public:
  // `fetcher` must outlive the handler. retry_interval: least time between two requests while the
  // metadata stays out of date (a sensor that cannot be reached is not hammered).
  OusterReinitHandler(OusterMetadataFetcher& fetcher, ouster::OusterDecoderOptions options,
                      Nanoseconds retry_interval = Nanoseconds(2'000'000'000));

  // Consumer thread, after StreamConsumer::poll(): asks for metadata when the consumer's
  // OusterDecoder reports a re-initialised sensor, or when the consumer has no decoder yet (the
  // daemon started without a metadata file and the sensor has not answered), and installs a new
  // decoder once it arrives. Does nothing if the consumer's decoder is not an OusterDecoder.
  void maintain(capture::StreamConsumer& consumer, HostTime now);

  // Consumer thread, with the source's latest health: a stream that recovered from STALE asks for
  // fresh metadata; writes sensor_reinits, metadata_refreshes and last_error into `health`.
  void note_health(capture::SourceHealth& health);

  [[nodiscard]] std::uint64_t sensor_reinits() const;
  [[nodiscard]] std::uint64_t metadata_refreshes() const { return refreshes_; }

 private:
  void ask(HostTime now);

  OusterMetadataFetcher& fetcher_;
  ouster::OusterDecoderOptions options_;
  Nanoseconds retry_interval_;
  std::optional<HostTime> last_request_;
  bool recovered_ = false;  // a STALE stream came back: refresh once
  std::uint64_t seen_recoveries_ = 0;
  std::uint64_t retired_reinits_ = 0;  // init_id changes counted by replaced decoders
  std::uint64_t current_reinits_ = 0;  // ... and by the current one (as of maintain())
  std::uint64_t refreshes_ = 0;
  std::uint64_t seen_failures_ = 0;  // fetcher failures already reported
  std::string last_error_;
};

}  // namespace livod::drivers::ouster
