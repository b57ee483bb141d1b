#include "drivers/ouster/sensor_api.hpp"

#include "core/error.hpp"

namespace livod::drivers::ouster {

std::string fetch_metadata_json(const std::string& host, std::uint16_t port,
                                std::chrono::milliseconds timeout) {
  io::HttpGetOptions options;
  options.timeout = timeout;
  io::HttpResponse r = io::http_get(host, port, std::string(kMetadataPath), options);
  if (r.status != 200) {
    throw livod::Error("HTTP GET http://" + host + ":" + std::to_string(port) +
                       std::string(kMetadataPath) + ": status " + std::to_string(r.status) + " " +
                       r.reason + ": " + r.body.substr(0, 200));
  }
  return std::move(r.body);
}

SensorMetadata fetch_metadata(const std::string& host, std::uint16_t port,
                              std::chrono::milliseconds timeout) {
  const std::string json = fetch_metadata_json(host, port, timeout);
  return parse_metadata(json,
                        "http://" + host + ":" + std::to_string(port) + std::string(kMetadataPath));
}

}  // namespace livod::drivers::ouster
