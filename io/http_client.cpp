#include "io/http_client.hpp"

#include <netdb.h>
#include <poll.h>
#include <sys/socket.h>
#include <unistd.h>

#include <algorithm>
#include <cctype>
#include <cerrno>
#include <charconv>
#include <cstring>
#include <memory>
#include <optional>
#include <string_view>
#include <utility>

#include "core/error.hpp"
#include "core/text.hpp"

namespace livod::io {
namespace {

using Clock = std::chrono::steady_clock;

class Socket {
 public:
  explicit Socket(int fd) : fd_(fd) {}
  ~Socket() {
    if (fd_ >= 0) ::close(fd_);
  }
  Socket(const Socket&) = delete;
  Socket& operator=(const Socket&) = delete;
  [[nodiscard]] int fd() const { return fd_; }
  int release() {
    const int fd = fd_;
    fd_ = -1;
    return fd;
  }

 private:
  int fd_;
};

struct AddrInfoDeleter {
  void operator()(addrinfo* a) const { ::freeaddrinfo(a); }
};

class Exchange {
 public:
  Exchange(std::string url, Clock::time_point deadline, std::size_t max_body)
      : url_(std::move(url)), deadline_(deadline), max_body_(max_body) {}

  [[noreturn]] void fail(const std::string& what) const {
    throw livod::Error("HTTP GET " + url_ + ": " + what);
  }

  // Waits for `events` on fd until the deadline.
  void wait(int fd, short events, const char* doing) const {
    for (;;) {
      const auto left =
          std::chrono::duration_cast<std::chrono::milliseconds>(deadline_ - Clock::now());
      if (left.count() <= 0) fail(std::string("timed out ") + doing);
      pollfd p{fd, events, 0};
      const int r = ::poll(&p, 1, static_cast<int>(std::min<long long>(left.count(), 1 << 30)));
      if (r > 0) return;
      if (r < 0 && errno != EINTR)
        fail(std::string("poll failed ") + doing + ": " + std::strerror(errno));
    }
  }

  int connect_any(const std::string& host, std::uint16_t port) const {
    addrinfo hints{};
    hints.ai_family = AF_UNSPEC;
    hints.ai_socktype = SOCK_STREAM;
    addrinfo* raw = nullptr;
    const std::string service = std::to_string(port);
    const int rc = ::getaddrinfo(host.c_str(), service.c_str(), &hints, &raw);
    if (rc != 0) fail(std::string("cannot resolve host: ") + ::gai_strerror(rc));
    const std::unique_ptr<addrinfo, AddrInfoDeleter> list(raw);
    std::string last_error = "no address";
    for (const addrinfo* a = list.get(); a != nullptr; a = a->ai_next) {
      const int fd =
          ::socket(a->ai_family, a->ai_socktype | SOCK_NONBLOCK | SOCK_CLOEXEC, a->ai_protocol);
      if (fd < 0) {
        last_error = std::strerror(errno);
        continue;
      }
      Socket guard(fd);
      if (::connect(fd, a->ai_addr, a->ai_addrlen) != 0) {
        if (errno != EINPROGRESS) {
          last_error = std::strerror(errno);
          continue;
        }
        wait(fd, POLLOUT, "connecting");
        int so_error = 0;
        socklen_t len = sizeof(so_error);
        ::getsockopt(fd, SOL_SOCKET, SO_ERROR, &so_error, &len);
        if (so_error != 0) {
          last_error = std::strerror(so_error);
          continue;
        }
      }
      return guard.release();
    }
    fail("cannot connect: " + last_error);
  }

  void send_all(int fd, std::string_view data) const {
    while (!data.empty()) {
      wait(fd, POLLOUT, "sending the request");
      const ssize_t n = ::send(fd, data.data(), data.size(), MSG_NOSIGNAL);
      if (n < 0) {
        if (errno == EAGAIN || errno == EINTR) continue;
        fail(std::string("send failed: ") + std::strerror(errno));
      }
      data.remove_prefix(static_cast<std::size_t>(n));
    }
  }

  // Appends what arrives to `buffer`; false at end of stream.
  bool receive_some(int fd, std::string& buffer) const {
    char chunk[16384];
    for (;;) {
      wait(fd, POLLIN, "waiting for the response");
      const ssize_t n = ::recv(fd, chunk, sizeof(chunk), 0);
      if (n > 0) {
        if (buffer.size() + static_cast<std::size_t>(n) > max_body_ + kMaxHeaderBytes) {
          fail("response larger than " + std::to_string(max_body_) + " bytes");
        }
        buffer.append(chunk, static_cast<std::size_t>(n));
        return true;
      }
      if (n == 0) return false;
      if (errno != EAGAIN && errno != EINTR)
        fail(std::string("recv failed: ") + std::strerror(errno));
    }
  }

  static constexpr std::size_t kMaxHeaderBytes = 64 * 1024;

 private:
  std::string url_;
  Clock::time_point deadline_;
  std::size_t max_body_;
};

std::string lower(std::string_view s) {
  std::string out(s);
  std::transform(out.begin(), out.end(), out.begin(),
                 [](unsigned char c) { return static_cast<char>(std::tolower(c)); });
  return out;
}

}  // namespace

HttpResponse http_get(const std::string& host, std::uint16_t port, const std::string& path,
                      const HttpGetOptions& options) {
  const bool ipv6_literal = host.find(':') != std::string::npos;
  const std::string authority =
      (ipv6_literal ? "[" + host + "]" : host) + (port == 80 ? "" : ":" + std::to_string(port));
  const Exchange ex("http://" + authority + path, Clock::now() + options.timeout,
                    options.max_body_bytes);
  if (path.empty() || path.front() != '/' || path.find_first_of("\r\n ") != std::string::npos) {
    ex.fail("path must start with '/' and contain no spaces or line breaks");
  }

  const Socket sock(ex.connect_any(host, port));
  ex.send_all(sock.fd(), "GET " + path + " HTTP/1.1\r\nHost: " + authority +
                             "\r\nAccept: application/json\r\nUser-Agent: livod\r\n"
                             "Connection: close\r\n\r\n");

  // Status line and headers.
  std::string buffer;
  std::size_t header_end = std::string::npos;
  while ((header_end = buffer.find("\r\n\r\n")) == std::string::npos) {
    if (buffer.size() > Exchange::kMaxHeaderBytes) ex.fail("response headers too long");
    if (!ex.receive_some(sock.fd(), buffer)) ex.fail("connection closed before the headers ended");
  }
  HttpResponse response;
  std::string_view head(buffer.data(), header_end);
  std::size_t line_end = head.find("\r\n");
  const std::string_view status_line = head.substr(0, line_end);
  if (status_line.rfind("HTTP/1.", 0) != 0 || status_line.size() < 12 || status_line[8] != ' ') {
    ex.fail("malformed status line '" + std::string(status_line.substr(0, 80)) + "'");
  }
  const auto sr = std::from_chars(status_line.data() + 9, status_line.data() + 12, response.status);
  if (sr.ec != std::errc() || sr.ptr != status_line.data() + 12 || response.status < 100) {
    ex.fail("malformed status code in '" + std::string(status_line.substr(0, 80)) + "'");
  }
  response.reason = std::string(
      trim_whitespace(status_line.substr(std::min<std::size_t>(12, status_line.size()))));

  std::optional<std::size_t> content_length;
  bool chunked = false;
  while (line_end != std::string_view::npos) {
    head.remove_prefix(line_end + 2);
    line_end = head.find("\r\n");
    const std::string_view line = head.substr(0, line_end);
    const std::size_t colon = line.find(':');
    if (colon == std::string_view::npos) continue;
    const std::string name = lower(trim_whitespace(line.substr(0, colon)));
    const std::string_view value = trim_whitespace(line.substr(colon + 1));
    if (name == "content-length") {
      std::size_t n = 0;
      const auto r = std::from_chars(value.data(), value.data() + value.size(), n);
      if (r.ec != std::errc() || r.ptr != value.data() + value.size()) {
        ex.fail("malformed Content-Length '" + std::string(value) + "'");
      }
      if (n > options.max_body_bytes) ex.fail("response larger than the limit");
      content_length = n;
    } else if (name == "transfer-encoding") {
      chunked = lower(value).find("chunked") != std::string::npos;
    } else if (name == "content-type") {
      response.content_type = std::string(value);
    }
  }

  std::string body = buffer.substr(header_end + 4);
  if (chunked) {
    // Decode chunks as they become complete: "<hex size>[;ext]\r\n<data>\r\n" ... "0\r\n\r\n".
    std::string raw = std::move(body);
    std::size_t pos = 0;
    for (;;) {
      const std::size_t eol = raw.find("\r\n", pos);
      if (eol == std::string::npos) {
        if (!ex.receive_some(sock.fd(), raw)) ex.fail("connection closed inside a chunk header");
        continue;
      }
      std::string_view size_text(raw.data() + pos, eol - pos);
      size_text = size_text.substr(0, size_text.find(';'));
      size_text = trim_whitespace(size_text);
      std::size_t size = 0;
      const auto r =
          std::from_chars(size_text.data(), size_text.data() + size_text.size(), size, 16);
      if (r.ec != std::errc() || r.ptr != size_text.data() + size_text.size()) {
        ex.fail("malformed chunk size '" + std::string(size_text.substr(0, 20)) + "'");
      }
      if (size > options.max_body_bytes || response.body.size() + size > options.max_body_bytes) {
        ex.fail("response larger than the limit");
      }
      if (size == 0) break;  // trailers, if any, are ignored
      while (raw.size() < eol + 2 + size + 2) {
        if (!ex.receive_some(sock.fd(), raw)) ex.fail("connection closed inside a chunk");
      }
      response.body.append(raw, eol + 2, size);
      if (raw.compare(eol + 2 + size, 2, "\r\n") != 0) ex.fail("chunk not followed by CRLF");
      pos = eol + 2 + size + 2;
    }
  } else if (content_length) {
    while (body.size() < *content_length) {
      if (!ex.receive_some(sock.fd(), body)) {
        ex.fail("connection closed after " + std::to_string(body.size()) + " of " +
                std::to_string(*content_length) + " body bytes");
      }
    }
    body.resize(*content_length);
    response.body = std::move(body);
  } else {
    while (ex.receive_some(sock.fd(), body)) {
    }
    response.body = std::move(body);
  }
  if (response.body.size() > options.max_body_bytes) ex.fail("response larger than the limit");
  return response;
}

}  // namespace livod::io
