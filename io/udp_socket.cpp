#include "io/udp_socket.hpp"

#include <arpa/inet.h>
#include <netinet/in.h>
#include <poll.h>
#include <sys/socket.h>
#include <unistd.h>

#include <cerrno>
#include <cstring>

#include "core/error.hpp"

namespace livod::io {
namespace {

std::string errno_text() {
  return std::strerror(errno);
}

// Control-message space for one SCM_TIMESTAMPNS and one SO_RXQ_OVFL per datagram.
constexpr std::size_t kControlBytes =
    CMSG_SPACE(sizeof(timespec)) + CMSG_SPACE(sizeof(std::uint32_t));

}  // namespace

std::uint32_t parse_ipv4(const std::string& text) {
  in_addr addr{};
  if (inet_pton(AF_INET, text.c_str(), &addr) != 1) {
    throw Error("invalid IPv4 address '" + text + "'");
  }
  return ntohl(addr.s_addr);
}

std::string format_ipv4(std::uint32_t host_order_ip) {
  in_addr addr{};
  addr.s_addr = htonl(host_order_ip);
  char buf[INET_ADDRSTRLEN] = {};
  inet_ntop(AF_INET, &addr, buf, sizeof(buf));
  return buf;
}

struct UdpSocket::Impl {
  int fd = -1;
  UdpSocketConfig config;
  int effective_rcvbuf = 0;
  UdpSocketCounters counters;
  RealtimeToMonotonic clock_offset;
  HostTime last_offset_refresh;

  std::vector<std::byte> payload_storage;  // batch_size * max_datagram_bytes
  std::vector<std::byte> control_storage;  // batch_size * kControlBytes
  std::vector<mmsghdr> headers;
  std::vector<iovec> iovecs;
  std::vector<sockaddr_in> sources;
  std::vector<ReceivedDatagram> received;

  ~Impl() {
    if (fd >= 0) ::close(fd);
  }

  void open() {
    fd = ::socket(AF_INET, SOCK_DGRAM | SOCK_CLOEXEC, 0);
    if (fd < 0) throw Error("udp socket: " + errno_text());
    const int one = 1;
    // SO_REUSEADDR lets a restarted daemon rebind at once and lets several listeners share a
    // multicast group.
    ::setsockopt(fd, SOL_SOCKET, SO_REUSEADDR, &one, sizeof(one));
    if (config.allow_broadcast) ::setsockopt(fd, SOL_SOCKET, SO_BROADCAST, &one, sizeof(one));
    if (::setsockopt(fd, SOL_SOCKET, SO_TIMESTAMPNS, &one, sizeof(one)) != 0) {
      throw Error("udp socket: SO_TIMESTAMPNS: " + errno_text());
    }
    if (::setsockopt(fd, SOL_SOCKET, SO_RXQ_OVFL, &one, sizeof(one)) != 0) {
      throw Error("udp socket: SO_RXQ_OVFL: " + errno_text());
    }
    const int want = config.receive_buffer_bytes;
    // SO_RCVBUFFORCE exceeds net.core.rmem_max when privileged; fall back to the capped request.
    if (::setsockopt(fd, SOL_SOCKET, SO_RCVBUFFORCE, &want, sizeof(want)) != 0) {
      ::setsockopt(fd, SOL_SOCKET, SO_RCVBUF, &want, sizeof(want));
    }
    socklen_t len = sizeof(effective_rcvbuf);
    ::getsockopt(fd, SOL_SOCKET, SO_RCVBUF, &effective_rcvbuf, &len);

    sockaddr_in addr{};
    addr.sin_family = AF_INET;
    addr.sin_port = htons(config.port);
    // A multicast receiver binds the group (or any) address so that only group traffic arrives.
    const std::string bind_to =
        config.multicast_group.empty() ? config.bind_address : config.multicast_group;
    addr.sin_addr.s_addr = htonl(parse_ipv4(bind_to));
    if (::bind(fd, reinterpret_cast<sockaddr*>(&addr), sizeof(addr)) != 0) {
      throw Error("udp socket: bind " + bind_to + ":" + std::to_string(config.port) + ": " +
                  errno_text());
    }
    if (!config.multicast_group.empty()) {
      ip_mreq mreq{};
      mreq.imr_multiaddr.s_addr = htonl(parse_ipv4(config.multicast_group));
      mreq.imr_interface.s_addr = htonl(parse_ipv4(config.multicast_interface));
      if (::setsockopt(fd, IPPROTO_IP, IP_ADD_MEMBERSHIP, &mreq, sizeof(mreq)) != 0) {
        throw Error("udp socket: join multicast " + config.multicast_group + ": " + errno_text());
      }
    }

    const std::size_t n = config.batch_size == 0 ? 1 : config.batch_size;
    payload_storage.resize(n * config.max_datagram_bytes);
    control_storage.resize(n * kControlBytes);
    headers.resize(n);
    iovecs.resize(n);
    sources.resize(n);
    received.resize(n);
    last_offset_refresh = host_now();
  }

  void arm() {
    for (std::size_t i = 0; i < headers.size(); ++i) {
      iovecs[i].iov_base = payload_storage.data() + i * config.max_datagram_bytes;
      iovecs[i].iov_len = config.max_datagram_bytes;
      msghdr& h = headers[i].msg_hdr;
      h = msghdr{};
      h.msg_name = &sources[i];
      h.msg_namelen = sizeof(sockaddr_in);
      h.msg_iov = &iovecs[i];
      h.msg_iovlen = 1;
      h.msg_control = control_storage.data() + i * kControlBytes;
      h.msg_controllen = kControlBytes;
      headers[i].msg_len = 0;
    }
  }

  std::span<const ReceivedDatagram> receive(int timeout_ms) {
    pollfd pfd{fd, POLLIN, 0};
    const int ready = ::poll(&pfd, 1, timeout_ms);
    if (ready <= 0) {
      if (ready < 0 && errno != EINTR) ++counters.receive_errors;
      return {};
    }
    arm();
    const int got = ::recvmmsg(fd, headers.data(), static_cast<unsigned>(headers.size()),
                               MSG_DONTWAIT, nullptr);
    if (got <= 0) {
      if (got < 0 && errno != EAGAIN && errno != EINTR) ++counters.receive_errors;
      return {};
    }
    const HostTime now = host_now();
    // Refresh the REALTIME->MONOTONIC offset at 10 Hz: NTP may step REALTIME at any time.
    if (now - last_offset_refresh > Nanoseconds(kRealtimeOffsetRefreshNs)) {
      clock_offset.refresh();
      last_offset_refresh = now;
    }
    for (int i = 0; i < got; ++i) {
      const msghdr& h = headers[static_cast<std::size_t>(i)].msg_hdr;
      ReceivedDatagram& d = received[static_cast<std::size_t>(i)];
      const std::size_t len = headers[static_cast<std::size_t>(i)].msg_len;
      d.truncated = (h.msg_flags & MSG_TRUNC) != 0;
      d.payload = std::span<const std::byte>(
          static_cast<const std::byte*>(iovecs[static_cast<std::size_t>(i)].iov_base),
          std::min(len, config.max_datagram_bytes));
      d.src_ip = ntohl(sources[static_cast<std::size_t>(i)].sin_addr.s_addr);
      d.src_port = ntohs(sources[static_cast<std::size_t>(i)].sin_port);
      d.rx = now;
      bool stamped = false;
      for (cmsghdr* c = CMSG_FIRSTHDR(const_cast<msghdr*>(&h)); c != nullptr;
           c = CMSG_NXTHDR(const_cast<msghdr*>(&h), c)) {
        if (c->cmsg_level != SOL_SOCKET) continue;
        if (c->cmsg_type == SCM_TIMESTAMPNS) {
          timespec ts{};
          std::memcpy(&ts, CMSG_DATA(c), sizeof(ts));
          d.rx = clock_offset.to_host(static_cast<std::int64_t>(ts.tv_sec) * 1'000'000'000 +
                                      ts.tv_nsec);
          stamped = true;
        } else if (c->cmsg_type == SO_RXQ_OVFL) {
          std::uint32_t drops = 0;
          std::memcpy(&drops, CMSG_DATA(c), sizeof(drops));
          counters.kernel_drops = drops;  // the kernel reports the socket's cumulative count
        }
      }
      if (!stamped) ++counters.missing_timestamps;
      if (d.truncated) ++counters.truncated;
      ++counters.datagrams;
      counters.bytes += len;
    }
    return {received.data(), static_cast<std::size_t>(got)};
  }
};

UdpSocket::UdpSocket(const UdpSocketConfig& config) : impl_(std::make_unique<Impl>()) {
  impl_->config = config;
  impl_->open();
}
UdpSocket::~UdpSocket() = default;
UdpSocket::UdpSocket(UdpSocket&&) noexcept = default;
UdpSocket& UdpSocket::operator=(UdpSocket&&) noexcept = default;

std::span<const ReceivedDatagram> UdpSocket::receive_batch(int timeout_ms) {
  return impl_->receive(timeout_ms);
}

bool UdpSocket::send_to(std::uint32_t dst_ip, std::uint16_t dst_port,
                        std::span<const std::byte> payload) {
  sockaddr_in addr{};
  addr.sin_family = AF_INET;
  addr.sin_port = htons(dst_port);
  addr.sin_addr.s_addr = htonl(dst_ip);
  const ssize_t sent = ::sendto(impl_->fd, payload.data(), payload.size(), 0,
                                reinterpret_cast<sockaddr*>(&addr), sizeof(addr));
  if (sent != static_cast<ssize_t>(payload.size())) {
    ++impl_->counters.receive_errors;
    return false;
  }
  return true;
}

std::uint16_t UdpSocket::local_port() const {
  sockaddr_in addr{};
  socklen_t len = sizeof(addr);
  ::getsockname(impl_->fd, reinterpret_cast<sockaddr*>(&addr), &len);
  return ntohs(addr.sin_port);
}

int UdpSocket::fd() const {
  return impl_->fd;
}
int UdpSocket::effective_receive_buffer_bytes() const {
  return impl_->effective_rcvbuf;
}
const UdpSocketCounters& UdpSocket::counters() const {
  return impl_->counters;
}

}  // namespace livod::io
