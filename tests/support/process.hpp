#pragma once
// Child processes for tests that drive real tools (lcm-logger, javac, the livod binary...): spawn
// with extra environment variables and output to a file, signal, wait with a timeout. A child
// still running when its ChildProcess is destroyed is killed and reaped, so a failing test
// leaves no process behind (which would also keep a test's network namespace alive).

#include <sys/types.h>

#include <chrono>
#include <filesystem>
#include <optional>
#include <string>
#include <vector>

namespace livod::test {

struct ProcessOptions {
  // stdout and stderr go to this file (truncated); empty: inherited from the test.
  std::filesystem::path output;
  // "NAME=value" entries added to (or replacing in) the test's environment.
  std::vector<std::string> environment;
};

class ChildProcess {
 public:
  // Starts argv[0] (searched in PATH). Throws std::runtime_error when it cannot be started.
  explicit ChildProcess(std::vector<std::string> argv, ProcessOptions options = {});
  ~ChildProcess();  // SIGKILL and reap if still running
  ChildProcess(const ChildProcess&) = delete;
  ChildProcess& operator=(const ChildProcess&) = delete;

  [[nodiscard]] pid_t pid() const { return pid_; }
  // True until the child has exited (reaps it when it has).
  bool running();
  void signal(int sig);
  // Exit status (128 + signal number when killed by a signal), or nullopt when the child is still
  // running after `timeout`.
  std::optional<int> wait_for(std::chrono::milliseconds timeout);

 private:
  pid_t pid_ = -1;
  std::optional<int> status_;
};

// Runs a command to completion. Returns its exit status (128 + signal when killed); a command
// still running after `timeout` is killed and -1 returned.
int run_process(std::vector<std::string> argv, const ProcessOptions& options = {},
                std::chrono::milliseconds timeout = std::chrono::seconds(120));

// The whole content of a text file ("" when it cannot be read).
std::string read_text_file(const std::filesystem::path& path);

}  // namespace livod::test
