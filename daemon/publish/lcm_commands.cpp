#include "daemon/publish/lcm_commands.hpp"

#include <lcm/lcm-cpp.hpp>

#include <chrono>
#include <vector>

#include "core/error.hpp"

#include "lcmtypes/livod/command_result_t.hpp"
#include "lcmtypes/livod/command_t.hpp"

namespace livod::daemon::publish {
namespace {

constexpr int kMaxMessagesPerPoll = 64;  // bounds one poll's work on the publisher thread

}  // namespace

struct LcmCommandChannel::Impl {
  lcm::LCM& lcm;
  std::string command_channel;
  std::string result_channel;
  lcm::Subscription* subscription = nullptr;
  std::vector<CommandRecord>* out = nullptr;  // set during poll()
  std::vector<std::uint8_t> buffer;
  std::uint64_t malformed = 0;
  std::uint64_t failed = 0;

  Impl(lcm::LCM& l, std::string command, std::string result)
      : lcm(l), command_channel(std::move(command)), result_channel(std::move(result)) {}

  void on_message(const lcm::ReceiveBuffer* rbuf, const std::string& /*channel*/) {
    livod::command_t m;
    if (m.decode(rbuf->data, 0, static_cast<int>(rbuf->data_size)) !=
        static_cast<int>(rbuf->data_size)) {
      ++malformed;  // the runtime logs the count
      return;
    }
    if (out == nullptr) return;
    CommandRecord c;
    c.request_id = m.request_id;
    c.sender = m.sender;
    c.command = m.command;
    c.argument = m.argument;
    out->push_back(std::move(c));
  }
};

LcmCommandChannel::LcmCommandChannel(lcm::LCM& lcm, std::string command_channel,
                                     std::string result_channel)
    : impl_(std::make_unique<Impl>(lcm, std::move(command_channel), std::move(result_channel))) {
  impl_->subscription = lcm.subscribe(impl_->command_channel, &Impl::on_message, impl_.get());
}

LcmCommandChannel::~LcmCommandChannel() {
  if (impl_->subscription != nullptr) impl_->lcm.unsubscribe(impl_->subscription);
}

void LcmCommandChannel::poll(std::vector<CommandRecord>& out) {
  impl_->out = &out;
  for (int i = 0; i < kMaxMessagesPerPoll; ++i) {
    if (impl_->lcm.handleTimeout(0) <= 0) break;
  }
  impl_->out = nullptr;
}

bool LcmCommandChannel::publish_result(const CommandResultRecord& r) {
  livod::command_result_t m;
  m.utime = r.unix_time_ns / 1000;
  m.request_id = r.request_id;
  m.requested_by = r.requested_by;
  m.command = r.command;
  m.status = static_cast<std::int8_t>(r.status);
  m.message = r.message;
  m.coalesced = r.coalesced;
  m.path = r.path;
  m.points = r.points;
  m.bytes = r.bytes;
  m.save_number = r.save_number;
  m.snapshot_utime = r.snapshot_unix_ns / 1000;
  m.duration_s = r.duration_s;
  const int size = m.getEncodedSize();
  impl_->buffer.resize(static_cast<std::size_t>(size));
  if (m.encode(impl_->buffer.data(), 0, size) != size ||
      impl_->lcm.publish(impl_->result_channel, impl_->buffer.data(),
                         static_cast<unsigned>(size)) != 0) {
    ++impl_->failed;
    return false;
  }
  return true;
}

std::uint64_t LcmCommandChannel::malformed() const {
  return impl_->malformed;
}

std::uint64_t LcmCommandChannel::failed() const {
  return impl_->failed;
}

namespace {

struct ResultWaiter {
  std::int64_t request_id = 0;
  std::optional<CommandResultRecord> result;

  void on_result(const lcm::ReceiveBuffer* /*rbuf*/, const std::string& /*channel*/,
                 const livod::command_result_t* m) {
    if (m->request_id != request_id || result) return;
    CommandResultRecord r;
    r.unix_time_ns = m->utime * 1000;
    r.request_id = m->request_id;
    r.requested_by = m->requested_by;
    r.command = m->command;
    r.status = static_cast<CommandStatus>(m->status);
    r.message = m->message;
    r.coalesced = m->coalesced;
    r.path = m->path;
    r.points = m->points;
    r.bytes = m->bytes;
    r.save_number = m->save_number;
    r.snapshot_unix_ns = m->snapshot_utime * 1000;
    r.duration_s = m->duration_s;
    result = std::move(r);
  }
};

}  // namespace

std::optional<CommandResultRecord> send_command(const std::string& url,
                                                const std::string& command_channel,
                                                const std::string& result_channel,
                                                const CommandRecord& command, int timeout_ms) {
  lcm::LCM lcm(url);
  if (!lcm.good()) throw Error("cannot initialise LCM with URL '" + url + "'");
  ResultWaiter waiter;
  waiter.request_id = command.request_id;
  lcm.subscribe(result_channel, &ResultWaiter::on_result, &waiter);
  livod::command_t m;
  m.utime = std::chrono::duration_cast<std::chrono::microseconds>(
                std::chrono::system_clock::now().time_since_epoch())
                .count();
  m.request_id = command.request_id;
  m.sender = command.sender;
  m.command = command.command;
  m.argument = command.argument;
  if (lcm.publish(command_channel, &m) != 0) {
    throw Error("cannot send the command on " + command_channel + " (LCM URL '" + url + "')");
  }
  const auto deadline = std::chrono::steady_clock::now() + std::chrono::milliseconds(timeout_ms);
  while (!waiter.result) {
    const auto left = std::chrono::duration_cast<std::chrono::milliseconds>(
                          deadline - std::chrono::steady_clock::now())
                          .count();
    if (left <= 0) break;
    lcm.handleTimeout(static_cast<int>(std::min<long long>(left, 100)));
  }
  return waiter.result;
}

}  // namespace livod::daemon::publish
