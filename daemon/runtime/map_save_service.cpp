#include "daemon/runtime/map_save_service.hpp"

#include <spdlog/spdlog.h>

#include <chrono>
#include <string_view>

#include "daemon/replay/map_accumulator.hpp"
#include "daemon/runtime/publisher.hpp"
#include "drivers/capture/doorbell.hpp"

namespace livod::daemon::runtime {
namespace {

std::int64_t unix_now_ns() {
  return std::chrono::duration_cast<std::chrono::nanoseconds>(
             std::chrono::system_clock::now().time_since_epoch())
      .count();
}

}  // namespace

MapSaverOptions map_saver_options(const std::filesystem::path& configured,
                                  const std::filesystem::path& out_dir,
                                  const char* state_directory_env, bool overwrite) {
  MapSaverOptions o;
  o.overwrite = overwrite;
  if (!configured.empty()) {
    o.directory = configured;
    return o;
  }
  o.create_directory = true;
  if (!out_dir.empty()) {
    o.directory = out_dir / "maps";
  } else if (state_directory_env != nullptr && *state_directory_env != '\0') {
    // StateDirectory= with several entries gives a colon-separated list: the first is livod's.
    const std::string_view list(state_directory_env);
    o.directory = std::filesystem::path(std::string(list.substr(0, list.find(':')))) / "maps";
  } else {
    o.directory = "maps";
  }
  return o;
}

MapSaveService::MapSaveService(MapSaveServiceOptions options, drivers::capture::Doorbell& wake)
    : options_(std::move(options)), wake_(wake), saver_(options_.saver, [&wake] { wake.ring(); }) {}

void MapSaveService::request_from_signal() {
  signals_.fetch_add(1, std::memory_order_relaxed);
  wake_.ring();
}

void MapSaveService::turn(const replay::MapAccumulator* map, MessageBus* bus) {
  if (const auto outcome = saver_.take_result()) answer(*outcome, bus);
  take_requests(bus);
  if (!new_requests_.empty()) start_or_join(map, bus);
}

void MapSaveService::finish(const replay::MapAccumulator* map, MessageBus* bus) {
  take_requests(bus);
  if (!new_requests_.empty()) start_or_join(map, bus);
  if (const auto outcome = saver_.wait()) answer(*outcome, bus);
  if (options_.enabled && options_.at_stop) {
    if (map == nullptr || map->size() == 0) {
      spdlog::info("no map to save at stop: no scan was registered");
      return;
    }
    new_requests_.push_back({0, "stop", false});
    ++stats_.requests;
    start_or_join(map, bus);
    if (const auto outcome = saver_.wait()) answer(*outcome, bus);
  }
}

void MapSaveService::take_requests(MessageBus* bus) {
  new_requests_.clear();
  const std::uint64_t signals = signals_.load(std::memory_order_relaxed);
  for (; signals_taken_ < signals; ++signals_taken_) {
    ++stats_.requests;
    if (!options_.enabled) {
      ++stats_.rejected;
      spdlog::warn("SIGUSR1: map saving is disabled (outputs.map_saves.enabled: false)");
      continue;
    }
    new_requests_.push_back({0, "SIGUSR1", false});
  }
  if (bus == nullptr) return;
  commands_.clear();
  bus->poll_commands(commands_);
  if (const std::uint64_t malformed = bus->malformed_commands(); malformed > malformed_logged_) {
    spdlog::warn("{} message(s) on the command channel were not livod.command_t: dropped",
                 malformed - malformed_logged_);
    malformed_logged_ = malformed;
  }
  for (auto& c : commands_) {
    publish::CommandResultRecord r;
    r.request_id = c.request_id;
    r.requested_by = c.sender;
    r.command = c.command;
    r.status = publish::CommandStatus::kRejected;
    if (c.command != static_cast<std::int8_t>(publish::Command::kSaveMap)) {
      r.message = "unknown command " + std::to_string(c.command);
    } else if (!c.argument.empty()) {
      r.message = "COMMAND_SAVE_MAP takes no argument (got '" + c.argument + "')";
    } else if (!options_.enabled) {
      r.message = "map saving is disabled (outputs.map_saves.enabled: false)";
    } else {
      ++stats_.requests;
      new_requests_.push_back({c.request_id, c.sender, false});
      continue;
    }
    ++stats_.rejected;
    spdlog::warn("command {} from '{}' (request {}) rejected: {}", c.command, c.sender,
                 c.request_id, r.message);
    reply(bus, std::move(r));
  }
}

void MapSaveService::start_or_join(const replay::MapAccumulator* map, MessageBus* bus) {
  if (saver_.busy()) {
    for (auto& w : new_requests_) {
      w.coalesced = true;
      ++stats_.coalesced;
      spdlog::info("map save requested by {} joins the save in progress", w.requested_by);
      joined_.push_back(std::move(w));
    }
    new_requests_.clear();
    return;
  }
  if (map == nullptr || map->size() == 0) {
    MapSaveOutcome empty;
    empty.error = "the map is empty: no scan has been registered yet";
    joined_ = std::move(new_requests_);
    new_requests_.clear();
    answer(empty, bus);
    return;
  }
  if (!saver_.start(map->xyz().data(), map->size(), unix_now_ns())) return;  // cannot happen
  joined_ = std::move(new_requests_);
  new_requests_.clear();
  for (std::size_t i = 1; i < joined_.size(); ++i) {
    joined_[i].coalesced = true;  // same turn: one save for all
    ++stats_.coalesced;
  }
}

void MapSaveService::answer(const MapSaveOutcome& outcome, MessageBus* bus) {
  ++(outcome.ok ? stats_.saved : stats_.failed);
  std::string who;
  for (const auto& w : joined_) who += (who.empty() ? "" : ", ") + w.requested_by;
  if (outcome.ok) {
    spdlog::info("map saved: {} ({} points, {:.1f} MB, {:.2f} s; requested by {})",
                 outcome.path.string(), outcome.points, static_cast<double>(outcome.bytes) / 1e6,
                 outcome.duration_s, who);
  } else {
    spdlog::error("map save failed (requested by {}): {}", who, outcome.error);
  }
  for (const auto& w : joined_) {
    publish::CommandResultRecord r;
    r.request_id = w.request_id;
    r.requested_by = w.requested_by;
    r.command = static_cast<std::int8_t>(publish::Command::kSaveMap);
    r.status = outcome.ok ? publish::CommandStatus::kOk : publish::CommandStatus::kFailed;
    r.message = outcome.error;
    r.coalesced = w.coalesced;
    if (outcome.ok) {
      r.path = outcome.path.string();
      r.points = static_cast<std::int64_t>(outcome.points);
      r.bytes = static_cast<std::int64_t>(outcome.bytes);
    }
    r.save_number = outcome.save_number;
    r.snapshot_unix_ns = outcome.snapshot_unix_ns;
    r.duration_s = outcome.duration_s;
    reply(bus, std::move(r));
  }
  joined_.clear();
}

void MapSaveService::reply(MessageBus* bus, publish::CommandResultRecord result) {
  if (bus == nullptr) return;
  result.unix_time_ns = unix_now_ns();
  bus->publish_command_result(result);
}

}  // namespace livod::daemon::runtime
