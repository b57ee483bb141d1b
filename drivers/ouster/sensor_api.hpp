#pragma once
// The parts of the Ouster HTTP API livod needs (FW >= 2.4; sensor-protocols.md §3.5). Older
// firmware only answers the TCP 7501 text protocol, which livod does not speak (an open item):
// record the metadata with the vendor tools once and pass the file instead.

#include <chrono>
#include <cstdint>
#include <string>

#include "drivers/ouster/metadata.hpp"
#include "io/http_client.hpp"

namespace livod::drivers::ouster {

inline constexpr std::string_view kMetadataPath = "/api/v1/sensor/metadata";

// GET /api/v1/sensor/metadata and return the body. Throws livod::Error on transport failures
// and on any status other than 200 (the message carries the status and the start of the body).
[[nodiscard]] std::string fetch_metadata_json(
    const std::string& host, std::uint16_t port = 80,
    std::chrono::milliseconds timeout = std::chrono::milliseconds(5000));

// fetch_metadata_json() + parse_metadata(); errors name "http://host/api/v1/sensor/metadata".
[[nodiscard]] SensorMetadata fetch_metadata(
    const std::string& host, std::uint16_t port = 80,
    std::chrono::milliseconds timeout = std::chrono::milliseconds(5000));

}  // namespace livod::drivers::ouster
