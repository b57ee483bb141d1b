// The live IMU sources end to end with real threads: frames into a socket (a socketpair standing
// in for a CAN_RAW socket) or bytes into a pseudo-terminal (a real tty, configured by termios),
// capture thread -> ring -> consumer -> decoder, and a device that vanishes and comes back.

#include "drivers/imu/imu_source.hpp"

#include <gtest/gtest.h>
#include <pty.h>
#include <sys/socket.h>
#include <unistd.h>

#include <chrono>
#include <filesystem>
#include <mutex>
#include <thread>

#include "core/error.hpp"
#include "drivers/imu/bosch_mm7.hpp"
#include "drivers/imu/xsens_mtdata2.hpp"
#include "tests/support/data_dir.hpp"

namespace livod::imu {
namespace {

using namespace std::chrono_literals;

// Polls `cond` (with `poll` run on the consumer side) for up to 10 s.
template <class Poll, class Cond>
bool wait_for(Poll&& poll, Cond&& cond) {
  const auto deadline = std::chrono::steady_clock::now() + 10s;
  while (std::chrono::steady_clock::now() < deadline) {
    poll();
    if (cond()) return true;
    std::this_thread::sleep_for(2ms);
  }
  poll();
  return cond();
}

// Socketpairs handed out as "CAN interfaces"; the test writes into the peer end.
class FakeBus {
 public:
  CanSocket open() {
    const std::lock_guard lock(mutex_);
    if (!available_) throw Error("SocketCAN interface 'fake0' does not exist");
    int fds[2];
    if (::socketpair(AF_UNIX, SOCK_SEQPACKET, 0, fds) != 0) throw Error("socketpair failed");
    if (peer_ >= 0) ::close(peer_);
    peer_ = fds[1];
    ++opens_;
    return CanSocket::adopt(fds[0], "fake0");
  }
  void send(const CanRecord& r) {
    const std::lock_guard lock(mutex_);
    const auto b = serialize_can_frame(r);
    ASSERT_EQ(::write(peer_, b.data(), b.size()), static_cast<ssize_t>(b.size()));
  }
  // The interface disappears: the open socket's peer closes, new opens fail.
  void unplug() {
    const std::lock_guard lock(mutex_);
    available_ = false;
    ::close(peer_);
    peer_ = -1;
  }
  void plug() {
    const std::lock_guard lock(mutex_);
    available_ = true;
  }
  int opens() {
    const std::lock_guard lock(mutex_);
    return opens_;
  }
  ~FakeBus() {
    if (peer_ >= 0) ::close(peer_);
  }

 private:
  std::mutex mutex_;
  int peer_ = -1;
  bool available_ = true;
  int opens_ = 0;
};

CanImuSourceConfig can_config(std::size_t ring) {
  CanImuSourceConfig c;
  c.name = "mm7";
  c.socket.interface = "fake0";
  c.ring_capacity = ring;
  c.thread.poll_timeout = 5ms;
  c.thread.reopen_interval = 20ms;
  c.timing.stale_after = 200ms;
  return c;
}

TEST(ImuSourceThreads, CanSourceDecodesReconnectsAfterTheInterfaceVanishes) {
  FakeBus bus;
  CanImuSource source(can_config(256), std::make_unique<BoschMm7Decoder>(),
                      [&] { return bus.open(); });
  std::vector<ImuSample> samples;
  auto poll = [&] { source.poll([&](const ImuSample& s) { samples.push_back(s); }); };
  const Eigen::Vector3d g(0.1, -0.2, 0.3);
  auto send_samples = [&](int first, int count) {
    for (int k = first; k < first + count; ++k) {
      const Eigen::Vector3d a(0.0, 0.0, 9.81 + 0.001 * k);
      for (const auto& f : encode_bosch_mm7_sample(static_cast<std::uint8_t>(k & 15), a, g, 30.0)) {
        bus.send(f);
      }
    }
  };
  send_samples(0, 50);
  ASSERT_TRUE(wait_for(poll, [&] { return samples.size() == 50; })) << samples.size();
  EXPECT_NEAR(samples[49].accel_m_s2.z(), 9.81 + 0.049, 0.001);
  // Receive stamps come from the socket, in order.
  for (std::size_t i = 1; i < samples.size(); ++i) {
    EXPECT_GE(samples[i].stamp.host, samples[i - 1].stamp.host);
  }
  auto h = source.update_health(host_now());
  EXPECT_EQ(h.source.device_state, "STREAMING");
  EXPECT_EQ(h.source.streams.at(0).state, drivers::capture::StreamState::kStreaming);
  EXPECT_EQ(h.bus.frames, 150u);
  EXPECT_EQ(h.decoder.samples, 50u);

  // The interface goes away: LOST, reopen attempts fail and are counted, STALE in health.
  bus.unplug();
  ASSERT_TRUE(wait_for(poll, [&] { return source.device_counters().open_failures >= 2; }));
  EXPECT_EQ(source.device_counters().state, drivers::capture::DeviceState::kLost);
  EXPECT_EQ(source.device_counters().losses, 1u);
  std::this_thread::sleep_for(250ms);
  h = source.update_health(host_now());
  EXPECT_EQ(h.source.streams.at(0).state, drivers::capture::StreamState::kStale);
  EXPECT_NE(h.source.last_error.find("fake0"), std::string::npos) << h.source.last_error;

  // It comes back: reopened without restarting anything, and the stream continues.
  bus.plug();
  ASSERT_TRUE(wait_for(poll, [&] { return source.device_counters().reconnects == 1; }));
  send_samples(50, 30);
  ASSERT_TRUE(wait_for(poll, [&] { return samples.size() == 80; })) << samples.size();
  h = source.update_health(host_now());
  EXPECT_EQ(h.source.streams.at(0).state, drivers::capture::StreamState::kStreaming);
  EXPECT_EQ(h.source.streams.at(0).stale_events, 1u);
  EXPECT_EQ(h.source.streams.at(0).recoveries, 1u);
  EXPECT_EQ(h.source.reconnects, 1u);
  EXPECT_EQ(h.source.last_error, "") << "the loss is history once it streams again";
  EXPECT_EQ(h.bus.frames, 240u);  // totals across sockets
  EXPECT_EQ(h.decoder.sequence_gaps, 0u);
  EXPECT_GT(h.device.wakeups, 10u);
  source.stop();
  EXPECT_EQ(source.device_counters().state, drivers::capture::DeviceState::kStopped);
}

TEST(ImuSourceThreads, AFullRingDropsTheNewestFramesAndCountsThem) {
  FakeBus bus;
  CanImuSource source(can_config(8), std::make_unique<BoschMm7Decoder>(),
                      [&] { return bus.open(); });
  const Eigen::Vector3d z = Eigen::Vector3d::Zero();
  for (int k = 0; k < 40; ++k) {
    for (const auto& f : encode_bosch_mm7_sample(static_cast<std::uint8_t>(k & 15), z, z, 20.0)) {
      bus.send(f);
    }
  }
  // Nobody polls: the ring holds the first 8 frames, the other 112 are dropped and counted.
  ASSERT_TRUE(wait_for([] {}, [&] { return source.bus_counters().frames == 120; }));
  auto h = source.update_health(host_now());
  EXPECT_EQ(h.ring_overruns, 112u);
  EXPECT_EQ(h.source.streams.at(0).capture.pushed, 8u);
  std::vector<ImuSample> samples;
  source.poll([&](const ImuSample& s) { samples.push_back(s); });
  EXPECT_EQ(samples.size(), 2u);  // frames 0..7: samples 0 and 1 complete, 2 cut short
}

TEST(ImuSourceThreads, AMissingCanInterfaceFailsAtConstruction) {
  CanImuSourceConfig c = can_config(16);
  c.socket.interface = "livodcan9";
  try {
    CanImuSource source(c, std::make_unique<BoschMm7Decoder>());
    FAIL() << "constructed a source on a missing interface";
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find("livodcan9"), std::string::npos) << e.what();
  }
}

// A pseudo-terminal pair whose slave is reachable through a stable symlink (like
// /dev/serial/by-id/...): re-plugging the "adapter" makes a new pty and moves the link.
class FakeTty {
 public:
  explicit FakeTty(std::filesystem::path link) : link_(std::move(link)) { plug(); }
  ~FakeTty() { unplug(); }
  void plug() {
    int slave = -1;
    ASSERT_EQ(::openpty(&master_, &slave, nullptr, nullptr, nullptr), 0);
    const std::string name = ::ttyname(slave);
    ::close(slave);  // the source opens it by path
    std::filesystem::remove(link_);
    std::filesystem::create_symlink(name, link_);
  }
  void unplug() {
    if (master_ >= 0) ::close(master_);
    master_ = -1;
    std::filesystem::remove(link_);
  }
  void write(const std::vector<std::uint8_t>& bytes) {
    ASSERT_EQ(::write(master_, bytes.data(), bytes.size()), static_cast<ssize_t>(bytes.size()));
  }

 private:
  std::filesystem::path link_;
  int master_ = -1;
};

TEST(ImuSourceThreads, SerialSourceDecodesAnXsensStreamFromARealTtyAndReopensIt) {
  const auto dir = test::temp_dir("imu_source_tty");
  const auto link = dir / "xsens";
  FakeTty tty(link);
  SerialImuSourceConfig c;
  c.name = "xsens";
  c.path = link.string();
  c.baud_rate = 921600;
  c.thread.poll_timeout = 5ms;
  c.thread.reopen_interval = 20ms;
  c.timing.stale_after = 200ms;
  SerialImuSource source(c, std::make_unique<XsensMtData2Decoder>());
  std::vector<ImuSample> samples;
  auto poll = [&] { source.poll([&](const ImuSample& s) { samples.push_back(s); }); };
  auto send = [&](int first, int count) {
    std::vector<std::uint8_t> stream;
    for (int k = first; k < first + count; ++k) {
      XsensSample x;
      x.packet_counter = static_cast<std::uint16_t>(k);
      x.sample_time_fine = static_cast<std::uint32_t>(25 * k);
      x.accel_m_s2 = Eigen::Vector3d(k, 0.0, 9.81);
      const auto m = encode_mtdata2_sample(x);
      stream.insert(stream.end(), m.begin(), m.end());
    }
    // Written in odd pieces: the reads see torn messages.
    for (std::size_t i = 0; i < stream.size(); i += 37) {
      tty.write({stream.begin() + static_cast<std::ptrdiff_t>(i),
                 stream.begin() + static_cast<std::ptrdiff_t>(std::min(stream.size(), i + 37))});
    }
  };
  send(0, 100);
  ASSERT_TRUE(wait_for(poll, [&] { return samples.size() == 100; })) << samples.size();
  for (std::size_t k = 0; k < samples.size(); ++k) {
    EXPECT_EQ(samples[k].accel_m_s2.x(), static_cast<double>(k));
    EXPECT_EQ(samples[k].stamp.sensor.ns, static_cast<std::int64_t>(25 * k) * 100'000);
  }
  // Unplugged: hang-up -> LOST; the device path is gone, reopening fails until it returns.
  tty.unplug();
  ASSERT_TRUE(wait_for(poll, [&] { return source.device_counters().open_failures >= 2; }));
  EXPECT_EQ(source.device_counters().losses, 1u);
  tty.plug();
  ASSERT_TRUE(wait_for(poll, [&] { return source.device_counters().reconnects == 1; }));
  send(100, 50);
  ASSERT_TRUE(wait_for(poll, [&] { return samples.size() == 150; })) << samples.size();
  const auto h = source.update_health(host_now());
  EXPECT_EQ(h.decoder.sequence_gaps, 0u);
  EXPECT_EQ(h.decoder.checksum_errors, 0u);
  EXPECT_EQ(h.source.reconnects, 1u);
  EXPECT_EQ(h.ring_overruns, 0u);
}

// `livod run`'s policy (wait_for_device): a device missing at start-up is not an error but a
// device not there yet: the source reports why (state OPENING, last_error naming the path), keeps
// trying, and streams once the device appears (a robot booting before its USB IMU enumerates).
// Data rings the consumer's doorbell.
TEST(ImuSourceThreads, ASerialDeviceMissingAtStartIsWaitedForWhenAsked) {
  const auto dir = test::temp_dir("imu_source_late_tty");
  const auto link = dir / "late-xsens";
  std::filesystem::remove(link);
  drivers::capture::Doorbell doorbell;
  SerialImuSourceConfig c;
  c.name = "xsens";
  c.path = link.string();
  c.thread.poll_timeout = 5ms;
  c.thread.reopen_interval = 20ms;
  c.thread.wait_for_device = true;
  c.thread.doorbell = &doorbell;
  c.timing.stale_after = 200ms;
  SerialImuSource source(c, std::make_unique<XsensMtData2Decoder>());
  std::vector<ImuSample> samples;
  auto poll = [&] { source.poll([&](const ImuSample& s) { samples.push_back(s); }); };
  ASSERT_TRUE(wait_for(poll, [&] { return source.device_counters().open_failures >= 3; }));
  auto d = source.device_counters();
  EXPECT_EQ(d.state, drivers::capture::DeviceState::kOpening);
  EXPECT_EQ(d.opens, 0u);
  auto h = source.update_health(host_now());
  EXPECT_NE(h.source.last_error.find(link.string() + " does not exist"), std::string::npos)
      << h.source.last_error;
  EXPECT_EQ(h.source.device_state, "OPENING");

  FakeTty tty(link);
  ASSERT_TRUE(wait_for(poll, [&] { return source.device_counters().opens == 1; }));
  const std::uint32_t token = doorbell.prepare();
  std::vector<std::uint8_t> stream;
  for (int k = 0; k < 20; ++k) {
    XsensSample x;
    x.packet_counter = static_cast<std::uint16_t>(k);
    x.sample_time_fine = static_cast<std::uint32_t>(25 * k);
    const auto m = encode_mtdata2_sample(x);
    stream.insert(stream.end(), m.begin(), m.end());
  }
  tty.write(stream);
  doorbell.wait(token, 5s);  // rung by the capture thread (returns at once if already rung)
  EXPECT_NE(doorbell.prepare(), token);
  ASSERT_TRUE(wait_for(poll, [&] { return samples.size() == 20; })) << samples.size();
  d = source.device_counters();
  EXPECT_EQ(d.state, drivers::capture::DeviceState::kStreaming);
  EXPECT_EQ(d.reconnects, 0u) << "a late first open is not a reconnect";
  EXPECT_EQ(d.losses, 0u);
}

TEST(ImuSourceThreads, AMissingSerialDeviceFailsAtConstructionNamingIt) {
  SerialImuSourceConfig c;
  c.name = "xsens";
  c.path = "/dev/livod-no-such-tty";
  try {
    SerialImuSource source(c, std::make_unique<XsensMtData2Decoder>());
    FAIL();
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find("/dev/livod-no-such-tty does not exist"),
              std::string::npos)
        << e.what();
  }
  c.path = "usb:2639:zz";
  EXPECT_THROW(SerialImuSource(c, std::make_unique<XsensMtData2Decoder>()), Error);
}

}  // namespace
}  // namespace livod::imu
