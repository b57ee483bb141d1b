#pragma once
// A minimal blocking HTTP/1.1 GET client over one TCP connection, enough for a sensor's REST API
// (no TLS, no redirects, no keep-alive). Bodies with Content-Length, chunked transfer encoding or
// read-until-close are supported. One deadline bounds the whole exchange (resolve excepted, which
// is only slow for names, not for the IP addresses sensors are configured with).

#include <chrono>
#include <cstddef>
#include <cstdint>
#include <string>

namespace livod::io {

struct HttpResponse {
  int status = 0;  // e.g. 200
  std::string reason;
  std::string content_type;
  std::string body;
};

struct HttpGetOptions {
  std::chrono::milliseconds timeout{5000};
  std::size_t max_body_bytes = 16U << 20U;  // a sensor's metadata is ~10-50 KB
};

// GET http://host:port/path. Returns any HTTP status (the caller decides what is acceptable);
// throws livod::Error naming the URL on resolve/connect failure, timeout, a connection closed
// early, an oversized or malformed response.
[[nodiscard]] HttpResponse http_get(const std::string& host, std::uint16_t port,
                                    const std::string& path, const HttpGetOptions& options = {});

}  // namespace livod::io
