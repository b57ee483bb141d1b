#pragma once
// Requests to a running livod and their answers (livod.command_t / livod.command_result_t on
// LIVOD_COMMAND / LIVOD_COMMAND_RESULT, docs/lcm.md), as plain structs: the runtime does not see
// the generated LCM types. daemon/publish/lcm_commands.hpp decodes and encodes them.

#include <cstdint>
#include <string>

namespace livod::daemon::publish {

// livod.command_t.COMMAND_*.
enum class Command : std::int8_t {
  kSaveMap = 1,
};

// livod.command_result_t.STATUS_*.
enum class CommandStatus : std::int8_t {
  kOk = 0,
  kFailed = 1,    // understood, carried out, failed (nothing written under the final name)
  kRejected = 2,  // not carried out: unknown command, unexpected argument, feature disabled
};

struct CommandRecord {
  std::int64_t request_id = 0;
  std::string sender;
  std::int8_t command = 0;  // as received: may be a value livod does not know
  std::string argument;
};

struct CommandResultRecord {
  std::int64_t unix_time_ns = 0;  // when the result is published
  std::int64_t request_id = 0;    // 0 when no command asked (SIGUSR1, stop)
  std::string requested_by;       // the command's sender, "SIGUSR1" or "stop"
  std::int8_t command = static_cast<std::int8_t>(Command::kSaveMap);
  CommandStatus status = CommandStatus::kOk;
  std::string message;
  bool coalesced = false;  // joined a save already in progress
  // COMMAND_SAVE_MAP
  std::string path;
  std::int64_t points = 0;
  std::int64_t bytes = 0;
  std::int32_t save_number = 0;
  std::int64_t snapshot_unix_ns = 0;
  double duration_s = 0.0;
};

}  // namespace livod::daemon::publish
