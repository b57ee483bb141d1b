// The HTTP metadata path against a tiny HTTP server on 127.0.0.1 (a thread in this test) that
// serves a real metadata file. No external address is contacted.

#include <arpa/inet.h>
#include <netinet/in.h>
#include <poll.h>
#include <sys/socket.h>
#include <unistd.h>

#include <gtest/gtest.h>

#include <fstream>
#include <functional>
#include <sstream>
#include <stdexcept>
#include <thread>

#include "drivers/ouster/sensor_api.hpp"
#include "io/http_client.hpp"
#include "tests/support/data_dir.hpp"

namespace livod::drivers::ouster {
namespace {

using io::http_get;
using io::HttpGetOptions;
using io::HttpResponse;

std::string read_text(const std::filesystem::path& p) {
  std::ifstream in(p, std::ios::binary);
  std::ostringstream s;
  s << in.rdbuf();
  return s.str();
}

// Accepts one connection, records the request, answers with `response` (or, when `silent`,
// never answers and waits for the client to give up), then closes.
class OneShotServer {
 public:
  explicit OneShotServer(std::string response, bool silent = false)
      : response_(std::move(response)), silent_(silent) {
    listen_fd_ = ::socket(AF_INET, SOCK_STREAM | SOCK_CLOEXEC, 0);
    sockaddr_in addr{};
    addr.sin_family = AF_INET;
    addr.sin_addr.s_addr = htonl(INADDR_LOOPBACK);
    addr.sin_port = 0;
    if (listen_fd_ < 0 ||
        ::bind(listen_fd_, reinterpret_cast<sockaddr*>(&addr), sizeof(addr)) != 0 ||
        ::listen(listen_fd_, 1) != 0) {
      throw std::runtime_error("test server setup failed");
    }
    socklen_t len = sizeof(addr);
    ::getsockname(listen_fd_, reinterpret_cast<sockaddr*>(&addr), &len);
    port_ = ntohs(addr.sin_port);
    thread_ = std::thread([this] { serve(); });
  }
  ~OneShotServer() {
    if (thread_.joinable()) thread_.join();
    ::close(listen_fd_);
  }
  OneShotServer(const OneShotServer&) = delete;
  OneShotServer& operator=(const OneShotServer&) = delete;

  [[nodiscard]] std::uint16_t port() const { return port_; }
  std::string request() {
    if (thread_.joinable()) thread_.join();
    return request_;
  }

 private:
  void serve() {
    // Bounded wait, so that a client failing before it connects cannot hang the test.
    pollfd p{listen_fd_, POLLIN, 0};
    if (::poll(&p, 1, 10000) != 1) return;
    const int fd = ::accept(listen_fd_, nullptr, nullptr);
    if (fd < 0) return;
    char buf[4096];
    while (request_.find("\r\n\r\n") == std::string::npos) {
      const ssize_t n = ::recv(fd, buf, sizeof(buf), 0);
      if (n <= 0) break;
      request_.append(buf, static_cast<std::size_t>(n));
    }
    if (silent_) {
      while (::recv(fd, buf, sizeof(buf), 0) > 0) {
      }
    } else {
      std::size_t sent = 0;
      while (sent < response_.size()) {
        const ssize_t n =
            ::send(fd, response_.data() + sent, response_.size() - sent, MSG_NOSIGNAL);
        if (n <= 0) break;
        sent += static_cast<std::size_t>(n);
      }
    }
    ::close(fd);
  }

  std::string response_;
  bool silent_;
  int listen_fd_ = -1;
  std::uint16_t port_ = 0;
  std::thread thread_;
  std::string request_;
};

std::string with_length(const std::string& body, const std::string& status = "200 OK") {
  return "HTTP/1.1 " + status +
         "\r\nContent-Type: application/json\r\nContent-Length: " + std::to_string(body.size()) +
         "\r\nConnection: close\r\n\r\n" + body;
}

std::string chunked(const std::string& body) {
  std::ostringstream out;
  out << "HTTP/1.1 200 OK\r\ncontent-type: application/json\r\nTransfer-Encoding: chunked\r\n\r\n";
  for (std::size_t pos = 0; pos < body.size(); pos += 1000) {
    const std::string part = body.substr(pos, 1000);
    out << std::hex << part.size() << (pos == 0 ? ";ext=1" : "") << "\r\n" << part << "\r\n";
  }
  out << "0\r\n\r\n";
  return out.str();
}

TEST(OusterHttp, FetchesAndParsesMetadata) {
  const auto path = test::data_path("ouster/pcaps/crc_test.json");
  const std::string body = read_text(path);
  OneShotServer server(with_length(body));
  const SensorMetadata fetched = fetch_metadata("127.0.0.1", server.port());
  const SensorMetadata from_file = load_metadata(path);
  EXPECT_EQ(fetched.prod_sn, from_file.prod_sn);
  EXPECT_EQ(fetched.initialization_id, from_file.initialization_id);
  EXPECT_EQ(fetched.beam_altitude_angles_deg, from_file.beam_altitude_angles_deg);
  EXPECT_EQ(fetched.format.pixel_shift_by_row, from_file.format.pixel_shift_by_row);
  EXPECT_EQ(fetched.T_sensor_lidar_mm, from_file.T_sensor_lidar_mm);
  const std::string request = server.request();
  EXPECT_EQ(request.rfind("GET /api/v1/sensor/metadata HTTP/1.1\r\n", 0), 0U) << request;
  EXPECT_NE(request.find("\r\nHost: 127.0.0.1:" + std::to_string(server.port()) + "\r\n"),
            std::string::npos)
      << request;
}

TEST(OusterHttp, ChunkedAndUntilCloseBodies) {
  const std::string body = read_text(test::data_path("ouster/pcaps/imu_zm_no_lidar_0.json"));
  ASSERT_GT(body.size(), 40000U);
  {
    OneShotServer server(chunked(body));
    const HttpResponse r = http_get("127.0.0.1", server.port(), "/api/v1/sensor/metadata");
    EXPECT_EQ(r.status, 200);
    EXPECT_EQ(r.content_type, "application/json");
    EXPECT_EQ(r.body, body);
  }
  {
    OneShotServer server("HTTP/1.0 200 OK\r\n\r\n" + body);
    const HttpResponse r = http_get("127.0.0.1", server.port(), "/x");
    EXPECT_EQ(r.status, 200);
    EXPECT_EQ(r.body, body);
  }
  {
    OneShotServer server(chunked(body));
    EXPECT_EQ(fetch_metadata("127.0.0.1", server.port()).format.udp_profile_imu,
              ImuProfile::kAccel32Gyro32Nmea);
  }
}

void expect_error(const std::function<void()>& f, const std::string& fragment) {
  try {
    f();
    ADD_FAILURE() << "no error, expected: " << fragment;
  } catch (const livod::Error& e) {
    EXPECT_NE(std::string(e.what()).find(fragment), std::string::npos) << e.what();
  }
}

TEST(OusterHttp, FailuresAreReportedWithTheUrl) {
  {
    OneShotServer server(with_length("no such resource", "404 Not Found"));
    const std::uint16_t port = server.port();
    expect_error([&] { (void)fetch_metadata_json("127.0.0.1", port); },
                 "/api/v1/sensor/metadata: status 404 Not Found: no such resource");
  }
  {
    OneShotServer server("HTTP/1.1 200 OK\r\nContent-Length: 100000\r\n\r\n{\"beam\"");
    const std::uint16_t port = server.port();
    expect_error([&] { (void)fetch_metadata("127.0.0.1", port); },
                 "connection closed after 7 of 100000 body bytes");
  }
  {
    OneShotServer server(with_length("{\"sensor_info\": 1"));
    const std::uint16_t port = server.port();
    expect_error(
        [&] { (void)fetch_metadata("127.0.0.1", port); },
        "http://127.0.0.1:" + std::to_string(port) + "/api/v1/sensor/metadata: at byte offset");
  }
  {
    OneShotServer server("garbage\r\n\r\n");
    const std::uint16_t port = server.port();
    expect_error([&] { (void)http_get("127.0.0.1", port, "/"); },
                 "malformed status line 'garbage'");
  }
  {
    OneShotServer server("HTTP/1.1 200 OK\r\nTransfer-Encoding: chunked\r\n\r\nzz\r\n");
    const std::uint16_t port = server.port();
    expect_error([&] { (void)http_get("127.0.0.1", port, "/"); }, "malformed chunk size 'zz'");
  }
  {
    // The server accepts and never answers: the deadline ends the exchange.
    OneShotServer server("", true);
    const std::uint16_t port = server.port();
    expect_error(
        [&] { (void)fetch_metadata_json("127.0.0.1", port, std::chrono::milliseconds(200)); },
        "timed out waiting for the response");
  }
  {
    // Nothing listens on a port that was just released.
    const int fd = ::socket(AF_INET, SOCK_STREAM, 0);
    sockaddr_in addr{};
    addr.sin_family = AF_INET;
    addr.sin_addr.s_addr = htonl(INADDR_LOOPBACK);
    ASSERT_EQ(::bind(fd, reinterpret_cast<sockaddr*>(&addr), sizeof(addr)), 0);
    socklen_t len = sizeof(addr);
    ::getsockname(fd, reinterpret_cast<sockaddr*>(&addr), &len);
    ::close(fd);
    const std::uint16_t port = ntohs(addr.sin_port);
    expect_error([&] { (void)http_get("127.0.0.1", port, "/"); },
                 "cannot connect: Connection refused");
  }
  expect_error([] { (void)http_get("127.0.0.1", 80, "no-slash"); }, "path must start with '/'");
  {
    HttpGetOptions small;
    small.max_body_bytes = 100;
    OneShotServer server(with_length(std::string(1000, 'x')));
    const std::uint16_t port = server.port();
    expect_error([&] { (void)http_get("127.0.0.1", port, "/", small); },
                 "response larger than the limit");
  }
}

}  // namespace
}  // namespace livod::drivers::ouster
