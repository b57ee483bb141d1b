// SocketCAN without a CAN interface (this machine has none): the frame and error-frame handling
// on struct can_frame images, the receive path (poll, recvmsg, SCM_TIMESTAMPNS, loss) on one end
// of a socketpair, and the clear failure of opening an interface the machine lacks.

#include "drivers/imu/socketcan.hpp"

#include <gtest/gtest.h>
#include <linux/can.h>
#include <linux/can/error.h>
#include <sys/socket.h>
#include <unistd.h>

#include "core/error.hpp"

namespace livod::imu {
namespace {

TEST(SocketCan, FramesRoundTripThroughTheKernelStructs) {
  CanRecord classic;
  classic.id = 0x174;
  classic.len = 8;
  for (int i = 0; i < 8; ++i) classic.data[i] = static_cast<std::uint8_t>(0x10 + i);
  CanRecord extended = classic;
  extended.id = 0x18FF0001;
  extended.extended = true;
  CanRecord fd = classic;
  fd.fd = true;
  fd.len = 48;
  CanRecord rtr;
  rtr.id = 0x123;
  rtr.rtr = true;
  for (const CanRecord& r : {classic, extended, fd, rtr}) {
    const auto bytes = serialize_can_frame(r);
    EXPECT_EQ(bytes.size(), r.fd ? CANFD_MTU : CAN_MTU);
    CanRecord back;
    ASSERT_TRUE(parse_can_frame(bytes, back));
    EXPECT_EQ(back.id, r.id);
    EXPECT_EQ(back.extended, r.extended);
    EXPECT_EQ(back.fd, r.fd);
    EXPECT_EQ(back.rtr, r.rtr);
    EXPECT_EQ(back.len, r.len);
    EXPECT_TRUE(std::equal(back.data.begin(), back.data.begin() + back.len, r.data.begin()));
  }
  // Sizes other than CAN_MTU / CANFD_MTU, and a classic length above 8, are rejected.
  std::vector<std::byte> odd(20);
  CanRecord out;
  EXPECT_FALSE(parse_can_frame(odd, out));
  auto bad = serialize_can_frame(classic);
  bad[4] = std::byte{9};  // can_frame.len
  EXPECT_FALSE(parse_can_frame(bad, out));
}

TEST(SocketCan, ErrorFramesAreClassified) {
  CanBusCounters c;
  CanRecord e;
  e.error = true;
  e.len = 8;
  e.id = CAN_ERR_BUSOFF;
  count_error_frame(e, c);
  e.id = CAN_ERR_CRTL;
  e.data[1] = CAN_ERR_CRTL_RX_PASSIVE | CAN_ERR_CRTL_RX_OVERFLOW;
  count_error_frame(e, c);
  e.id = CAN_ERR_RESTARTED;
  count_error_frame(e, c);
  e.id = CAN_ERR_PROT | CAN_ERR_ACK;
  count_error_frame(e, c);
  EXPECT_EQ(c.error_frames, 4u);
  EXPECT_EQ(c.bus_off, 1u);
  EXPECT_EQ(c.error_passive, 1u);
  EXPECT_EQ(c.controller_overflow, 1u);
  EXPECT_EQ(c.restarts, 1u);
  EXPECT_EQ(c.protocol_errors, 1u);
  // An error frame read from the socket image keeps its class bits in `id`.
  const auto bytes = serialize_can_frame(e);
  CanRecord back;
  ASSERT_TRUE(parse_can_frame(bytes, back));
  EXPECT_TRUE(back.error);
  EXPECT_EQ(back.id, CAN_ERR_PROT | CAN_ERR_ACK);
}

TEST(SocketCan, AMissingInterfaceFailsAtOpenNamingIt) {
  CanSocketConfig config;
  config.interface = "livodcan7";
  try {
    (void)CanSocket::open(config);
    FAIL() << "opened a CAN interface that does not exist";
  } catch (const Error& e) {
    // Either the kernel has no SocketCAN at all (this machine) or the interface is missing.
    EXPECT_NE(std::string(e.what()).find("'livodcan7'"), std::string::npos) << e.what();
  }
  config.interface = "name-longer-than-15";
  EXPECT_THROW((void)CanSocket::open(config), Error);
}

TEST(SocketCan, ReceivesStampedFramesAndReportsTheLossOfItsPeer) {
  int fds[2];
  ASSERT_EQ(::socketpair(AF_UNIX, SOCK_SEQPACKET, 0, fds), 0);
  CanSocket sock = CanSocket::adopt(fds[0], "pair0");
  const RealtimeToMonotonic clock;
  CanRecord f;
  f.id = 0x120;
  f.len = 8;
  CanRecord err;
  err.error = true;
  err.id = CAN_ERR_BUSOFF;
  err.len = 8;
  const std::int64_t before = host_now().ns;
  for (int i = 0; i < 5; ++i) {
    f.data[0] = static_cast<std::uint8_t>(i);
    const auto b = serialize_can_frame(i == 2 ? err : f);
    ASSERT_EQ(::write(fds[1], b.data(), b.size()), static_cast<ssize_t>(b.size()));
  }
  std::array<CanRecord, 3> out{};
  std::size_t n = 0;
  ASSERT_EQ(sock.receive(100, out, n, clock), CanSocket::Status::kOk);
  EXPECT_EQ(n, 3u);  // batch limit
  std::size_t m = 0;
  ASSERT_EQ(sock.receive(100, out, m, clock), CanSocket::Status::kOk);
  EXPECT_EQ(m, 2u);
  const std::int64_t after = host_now().ns;
  EXPECT_EQ(sock.counters().frames, 4u);
  EXPECT_EQ(sock.counters().error_frames, 1u);
  EXPECT_EQ(sock.counters().bus_off, 1u);
  EXPECT_EQ(out[1].data[0], 4);
  // Kernel (SCM_TIMESTAMPNS, realtime -> monotonic) or user-space stamps: both within the test.
  for (std::size_t i = 0; i < m; ++i) {
    EXPECT_GE(out[i].rx_time_ns, before - 1'000'000);
    EXPECT_LE(out[i].rx_time_ns, after + 1'000'000);
  }
  // Nothing queued: idle, not lost.
  ASSERT_EQ(sock.receive(10, out, n, clock), CanSocket::Status::kOk);
  EXPECT_EQ(n, 0u);
  ::close(fds[1]);
  EXPECT_EQ(sock.receive(100, out, n, clock), CanSocket::Status::kLost);
  EXPECT_NE(sock.loss_reason().find("pair0"), std::string::npos);
}

}  // namespace
}  // namespace livod::imu
