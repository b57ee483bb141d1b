#include "drivers/ouster/reinit.hpp"

#include <memory>
#include <utility>

#include "core/error.hpp"
#include "drivers/ouster/sensor_api.hpp"

namespace livod::drivers::ouster {

OusterMetadataFetcher::OusterMetadataFetcher(OusterMetadataFetcherConfig config)
    : config_(std::move(config)) {
  thread_ = std::jthread([this](const std::stop_token& stop) { run(stop); });
}

OusterMetadataFetcher::~OusterMetadataFetcher() {
  stop();
}

void OusterMetadataFetcher::stop() {
  if (thread_.joinable()) {
    thread_.request_stop();  // wakes the condition variable wait (stop_token overload)
    thread_.join();
  }
}

void OusterMetadataFetcher::request() {
  {
    const std::lock_guard lock(mutex_);
    if (requested_ || fetching_) return;
    requested_ = true;
    ++counters_.requests;
  }
  wake_.notify_one();
}

std::optional<ouster::SensorMetadata> OusterMetadataFetcher::take() {
  const std::lock_guard lock(mutex_);
  std::optional<ouster::SensorMetadata> out = std::move(ready_);
  ready_.reset();
  return out;
}

bool OusterMetadataFetcher::busy() const {
  const std::lock_guard lock(mutex_);
  return requested_ || fetching_;
}

OusterFetchCounters OusterMetadataFetcher::counters() const {
  const std::lock_guard lock(mutex_);
  return counters_;
}

std::string OusterMetadataFetcher::last_error() const {
  const std::lock_guard lock(mutex_);
  return last_error_;
}

void OusterMetadataFetcher::run(const std::stop_token& stop) {
  std::unique_lock lock(mutex_);
  for (;;) {
    if (!wake_.wait(lock, stop, [this] { return requested_; })) return;  // stop requested
    requested_ = false;
    fetching_ = true;
    lock.unlock();
    // The HTTP exchange runs unlocked: take()/request() never wait for the network.
    std::optional<ouster::SensorMetadata> metadata;
    std::string error;
    try {
      const std::string json =
          ouster::fetch_metadata_json(config_.host, config_.port, config_.timeout);
      metadata = ouster::parse_metadata(json, "http://" + config_.host + ":" +
                                                  std::to_string(config_.port) +
                                                  std::string(ouster::kMetadataPath));
      if (config_.on_fetched) config_.on_fetched(json);
    } catch (const Error& e) {
      error = e.what();
    }
    lock.lock();
    fetching_ = false;
    if (metadata) {
      ready_ = std::move(metadata);
      ++counters_.successes;
    } else {
      last_error_ = std::move(error);
      ++counters_.failures;
    }
  }
}

OusterReinitHandler::OusterReinitHandler(OusterMetadataFetcher& fetcher,
                                         ouster::OusterDecoderOptions options,
                                         Nanoseconds retry_interval)
    : fetcher_(fetcher), options_(options), retry_interval_(retry_interval) {}

void OusterReinitHandler::ask(HostTime now) {
  if (last_request_ && now - *last_request_ < retry_interval_) return;
  if (fetcher_.busy()) return;
  fetcher_.request();
  last_request_ = now;
}

void OusterReinitHandler::maintain(capture::StreamConsumer& consumer, HostTime now) {
  // No decoder yet (no metadata file; the sensor was unreachable at start): fetch until it answers.
  auto* decoder =
      consumer.has_decoder() ? dynamic_cast<ouster::OusterDecoder*>(&consumer.decoder()) : nullptr;
  if (consumer.has_decoder() && decoder == nullptr) return;
  if (decoder != nullptr) current_reinits_ = decoder->ouster_counters().init_id_changes;

  if (auto metadata = fetcher_.take()) {
    try {
      auto fresh = std::make_unique<ouster::OusterDecoder>(std::move(*metadata), options_);
      retired_reinits_ += current_reinits_;
      current_reinits_ = 0;
      consumer.replace_decoder(std::move(fresh));
      ++refreshes_;
      recovered_ = false;
      last_error_.clear();
      return;
    } catch (const Error& e) {
      last_error_ = std::string("metadata refresh: ") + e.what();
    }
  }
  if (decoder == nullptr || decoder->metadata_init_id_mismatch() || recovered_) ask(now);
  const OusterFetchCounters fetches = fetcher_.counters();
  if (fetches.failures != seen_failures_) {
    seen_failures_ = fetches.failures;
    last_error_ = "metadata refresh: " + fetcher_.last_error();
  }
}

void OusterReinitHandler::note_health(capture::SourceHealth& health) {
  std::uint64_t recoveries = 0;
  for (const capture::StreamHealth& s : health.streams) recoveries += s.recoveries;
  if (recoveries > seen_recoveries_) recovered_ = true;
  seen_recoveries_ = recoveries;
  health.sensor_reinits = sensor_reinits();
  health.metadata_refreshes = refreshes_;
  if (!last_error_.empty()) health.last_error = last_error_;
}

std::uint64_t OusterReinitHandler::sensor_reinits() const {
  return retired_reinits_ + current_reinits_;
}

}  // namespace livod::drivers::ouster
