#include "drivers/imu/socketcan.hpp"

#include <linux/can.h>
#include <linux/can/error.h>
#include <linux/can/raw.h>
#include <net/if.h>
#include <poll.h>
#include <sys/ioctl.h>
#include <sys/socket.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <cstring>
#include <ctime>
#include <utility>

#include "core/error.hpp"

namespace livod::imu {
namespace {

std::string errno_text(int err) {
  return std::strerror(err);
}

bool is_loss_errno(int err) {
  return err == ENETDOWN || err == ENODEV || err == ENXIO || err == EBADF || err == ENOTCONN ||
         err == ECONNRESET;
}

}  // namespace

void count_error_frame(const CanRecord& frame, CanBusCounters& c) {
  ++c.error_frames;
  const std::uint32_t cls = frame.id;
  if ((cls & CAN_ERR_BUSOFF) != 0) ++c.bus_off;
  if ((cls & CAN_ERR_RESTARTED) != 0) ++c.restarts;
  if ((cls & (CAN_ERR_PROT | CAN_ERR_BUSERROR | CAN_ERR_ACK | CAN_ERR_TRX | CAN_ERR_LOSTARB |
              CAN_ERR_TX_TIMEOUT)) != 0) {
    ++c.protocol_errors;
  }
  if ((cls & CAN_ERR_CRTL) != 0 && frame.len >= 2) {
    const std::uint8_t ctrl = frame.data[1];
    if ((ctrl & (CAN_ERR_CRTL_RX_PASSIVE | CAN_ERR_CRTL_TX_PASSIVE)) != 0) ++c.error_passive;
    if ((ctrl & (CAN_ERR_CRTL_RX_OVERFLOW | CAN_ERR_CRTL_TX_OVERFLOW)) != 0) {
      ++c.controller_overflow;
    }
  }
}

bool parse_can_frame(std::span<const std::byte> bytes, CanRecord& out) {
  const bool fd = bytes.size() == CANFD_MTU;
  if (!fd && bytes.size() != CAN_MTU) return false;
  canfd_frame f{};
  std::memcpy(&f, bytes.data(), bytes.size());
  const std::size_t max_len = fd ? CANFD_MAX_DLEN : CAN_MAX_DLEN;
  if (f.len > max_len) return false;
  out.fd = fd;
  out.error = (f.can_id & CAN_ERR_FLAG) != 0;
  out.rtr = !fd && (f.can_id & CAN_RTR_FLAG) != 0;
  out.extended = (f.can_id & CAN_EFF_FLAG) != 0;
  out.id = out.error ? (f.can_id & CAN_ERR_MASK)
                     : (f.can_id & (out.extended ? CAN_EFF_MASK : CAN_SFF_MASK));
  out.len = out.rtr ? 0 : f.len;
  std::memcpy(out.data.data(), f.data, out.len);
  return true;
}

std::vector<std::byte> serialize_can_frame(const CanRecord& r) {
  canfd_frame f{};
  f.can_id = r.id;
  if (r.extended) f.can_id |= CAN_EFF_FLAG;
  if (r.rtr) f.can_id |= CAN_RTR_FLAG;
  if (r.error) f.can_id = (r.id & CAN_ERR_MASK) | CAN_ERR_FLAG;
  f.len = r.len;
  std::memcpy(f.data, r.data.data(), std::min<std::size_t>(r.len, CANFD_MAX_DLEN));
  const std::size_t size = r.fd ? CANFD_MTU : CAN_MTU;
  std::vector<std::byte> out(size);
  std::memcpy(out.data(), &f, size);
  return out;
}

CanSocket CanSocket::open(const CanSocketConfig& config) {
  const std::string what = "SocketCAN interface '" + config.interface + "'";
  if (config.interface.empty() || config.interface.size() >= IFNAMSIZ) {
    throw Error(what + ": not a valid interface name");
  }
  const int fd = ::socket(PF_CAN, SOCK_RAW | SOCK_CLOEXEC, CAN_RAW);
  if (fd < 0) {
    const int err = errno;
    throw Error(what + ": cannot create a CAN_RAW socket (" + errno_text(err) + ")" +
                (err == EAFNOSUPPORT ? "; this kernel has no SocketCAN (modprobe can-raw)" : ""));
  }
  CanSocket sock(fd, config.interface);
  ifreq ifr{};
  std::strncpy(ifr.ifr_name, config.interface.c_str(), IFNAMSIZ - 1);
  if (::ioctl(fd, SIOCGIFINDEX, &ifr) < 0) {
    throw Error(what + " does not exist (" + errno_text(errno) + ")");
  }
  const int ifindex = ifr.ifr_ifindex;
  if (::ioctl(fd, SIOCGIFFLAGS, &ifr) == 0 && (ifr.ifr_flags & IFF_UP) == 0) {
    throw Error(what + " is down (ip link set " + config.interface + " up)");
  }
  const int on = 1;
  if (config.fd_frames && ::setsockopt(fd, SOL_CAN_RAW, CAN_RAW_FD_FRAMES, &on, sizeof(on)) < 0) {
    throw Error(what + ": CAN FD frames not supported (" + errno_text(errno) + ")");
  }
  if (!config.ids.empty()) {
    std::vector<can_filter> filters;
    for (const auto id : config.ids) {
      const bool ext = id > CAN_SFF_MASK;
      filters.push_back({ext ? (id | CAN_EFF_FLAG) : id,
                         (ext ? CAN_EFF_MASK : CAN_SFF_MASK) | CAN_EFF_FLAG | CAN_RTR_FLAG});
    }
    if (::setsockopt(fd, SOL_CAN_RAW, CAN_RAW_FILTER, filters.data(),
                     static_cast<socklen_t>(filters.size() * sizeof(can_filter))) < 0) {
      throw Error(what + ": cannot set the receive filter (" + errno_text(errno) + ")");
    }
  }
  if (config.error_frames) {
    const can_err_mask_t mask = CAN_ERR_MASK;
    ::setsockopt(fd, SOL_CAN_RAW, CAN_RAW_ERR_FILTER, &mask, sizeof(mask));
  }
  ::setsockopt(fd, SOL_SOCKET, SO_TIMESTAMPNS, &on, sizeof(on));
  ::setsockopt(fd, SOL_SOCKET, SO_RXQ_OVFL, &on, sizeof(on));
  if (config.receive_buffer_bytes > 0 &&
      ::setsockopt(fd, SOL_SOCKET, SO_RCVBUFFORCE, &config.receive_buffer_bytes, sizeof(int)) < 0) {
    ::setsockopt(fd, SOL_SOCKET, SO_RCVBUF, &config.receive_buffer_bytes, sizeof(int));
  }
  sockaddr_can addr{};
  addr.can_family = AF_CAN;
  addr.can_ifindex = ifindex;
  if (::bind(fd, reinterpret_cast<sockaddr*>(&addr), sizeof(addr)) < 0) {
    throw Error(what + ": cannot bind (" + errno_text(errno) + ")");
  }
  return sock;
}

CanSocket CanSocket::adopt(int fd, std::string name) {
  const int on = 1;
  ::setsockopt(fd, SOL_SOCKET, SO_TIMESTAMPNS, &on, sizeof(on));
  return CanSocket(fd, std::move(name));
}

CanSocket::CanSocket(CanSocket&& other) noexcept
    : fd_(std::exchange(other.fd_, -1)),
      name_(std::move(other.name_)),
      counters_(other.counters_),
      last_overflow_(other.last_overflow_),
      have_overflow_(other.have_overflow_),
      loss_reason_(std::move(other.loss_reason_)) {}

CanSocket& CanSocket::operator=(CanSocket&& other) noexcept {
  if (this != &other) {
    if (fd_ >= 0) ::close(fd_);
    fd_ = std::exchange(other.fd_, -1);
    name_ = std::move(other.name_);
    counters_ = other.counters_;
    last_overflow_ = other.last_overflow_;
    have_overflow_ = other.have_overflow_;
    loss_reason_ = std::move(other.loss_reason_);
  }
  return *this;
}

CanSocket::~CanSocket() {
  if (fd_ >= 0) ::close(fd_);
}

CanSocket::Status CanSocket::receive(int timeout_ms, std::span<CanRecord> out,
                                     std::size_t& received, const RealtimeToMonotonic& clock) {
  received = 0;
  pollfd pfd{fd_, POLLIN, 0};
  const int ready = ::poll(&pfd, 1, timeout_ms);
  if (ready < 0) {
    if (errno != EINTR) ++counters_.receive_errors;
    return Status::kOk;
  }
  if (ready == 0) return Status::kOk;
  if ((pfd.revents & (POLLERR | POLLHUP | POLLNVAL)) != 0 && (pfd.revents & POLLIN) == 0) {
    loss_reason_ = "CAN interface " + name_ + ": socket error or hang-up";
    return Status::kLost;
  }
  alignas(canfd_frame) std::byte frame[CANFD_MTU];
  alignas(cmsghdr)
      std::byte control[CMSG_SPACE(sizeof(timespec)) + CMSG_SPACE(sizeof(std::uint32_t))];
  while (received < out.size()) {
    iovec iov{frame, sizeof(frame)};
    msghdr msg{};
    msg.msg_iov = &iov;
    msg.msg_iovlen = 1;
    msg.msg_control = control;
    msg.msg_controllen = sizeof(control);
    const ssize_t n = ::recvmsg(fd_, &msg, MSG_DONTWAIT);
    if (n < 0) {
      const int err = errno;
      if (err == EAGAIN || err == EWOULDBLOCK || err == EINTR) break;
      if (is_loss_errno(err)) {
        loss_reason_ = "CAN interface " + name_ + ": " + errno_text(err);
        return Status::kLost;
      }
      ++counters_.receive_errors;
      break;
    }
    if (n == 0) {  // stream/seqpacket peer closed (adopted sockets): the "interface" is gone
      loss_reason_ = "CAN interface " + name_ + ": closed";
      return Status::kLost;
    }
    CanRecord& r = out[received];
    r = CanRecord{};
    if (!parse_can_frame({frame, static_cast<std::size_t>(n)}, r)) {
      ++counters_.receive_errors;
      continue;
    }
    bool stamped = false;
    for (cmsghdr* c = CMSG_FIRSTHDR(&msg); c != nullptr; c = CMSG_NXTHDR(&msg, c)) {
      if (c->cmsg_level != SOL_SOCKET) continue;
      if (c->cmsg_type == SCM_TIMESTAMPNS && c->cmsg_len >= CMSG_LEN(sizeof(timespec))) {
        timespec ts{};
        std::memcpy(&ts, CMSG_DATA(c), sizeof(ts));
        r.rx_time_ns = clock.to_host(std::int64_t{ts.tv_sec} * 1'000'000'000 + ts.tv_nsec).ns;
        stamped = true;
      } else if (c->cmsg_type == SO_RXQ_OVFL && c->cmsg_len >= CMSG_LEN(sizeof(std::uint32_t))) {
        std::uint32_t dropped = 0;
        std::memcpy(&dropped, CMSG_DATA(c), sizeof(dropped));
        // Cumulative per socket (wraps at 2^32): count the increase.
        if (have_overflow_)
          counters_.kernel_drops += static_cast<std::uint32_t>(dropped - last_overflow_);
        else
          counters_.kernel_drops += dropped;
        last_overflow_ = dropped;
        have_overflow_ = true;
      }
    }
    if (!stamped) {
      r.rx_time_ns = host_now().ns;
      ++counters_.missing_timestamps;
    }
    if (r.error) {
      count_error_frame(r, counters_);
    } else {
      ++counters_.frames;
      counters_.bytes += r.len;
    }
    ++received;
  }
  return Status::kOk;
}

}  // namespace livod::imu
