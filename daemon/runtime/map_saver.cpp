#include "daemon/runtime/map_saver.hpp"

#include <fcntl.h>
#include <pthread.h>
#include <sys/stat.h>
#include <unistd.h>

#include <cerrno>
#include <chrono>
#include <cstdio>
#include <cstring>
#include <ctime>
#include <system_error>

#include "io/pcd_writer.hpp"

namespace livod::daemon::runtime {
namespace {

std::string errno_text(int e) {
  return std::system_category().message(e);
}

// Writes all of [data, data + size) to fd; false with errno set on failure.
bool write_all(int fd, const char* data, std::size_t size) {
  while (size > 0) {
    const ssize_t n = ::write(fd, data, size);
    if (n < 0) {
      if (errno == EINTR) continue;
      return false;
    }
    data += n;
    size -= static_cast<std::size_t>(n);
  }
  return true;
}

class Fd {
 public:
  explicit Fd(int fd) : fd_(fd) {}
  ~Fd() {
    if (fd_ >= 0) ::close(fd_);
  }
  Fd(const Fd&) = delete;
  Fd& operator=(const Fd&) = delete;
  [[nodiscard]] int get() const { return fd_; }
  // close() and its error (a deferred write error surfaces here on some file systems).
  bool close() {
    const int fd = fd_;
    fd_ = -1;
    return ::close(fd) == 0;
  }

 private:
  int fd_;
};

}  // namespace

std::string map_file_name(std::int64_t snapshot_unix_ns, int number) {
  const std::time_t seconds = static_cast<std::time_t>(snapshot_unix_ns / 1'000'000'000);
  std::tm utc{};
  gmtime_r(&seconds, &utc);
  char stamp[32];
  std::strftime(stamp, sizeof stamp, "%Y%m%dT%H%M%SZ", &utc);
  char name[64];
  std::snprintf(name, sizeof name, "map-%s-%04d.pcd", stamp, number);
  return name;
}

MapSaver::MapSaver(MapSaverOptions options, std::function<void()> on_done)
    : options_(std::move(options)), on_done_(std::move(on_done)) {
  if (!options_.directory.empty()) {
    std::error_code ec;
    const auto absolute = std::filesystem::absolute(options_.directory, ec);
    if (!ec) options_.directory = absolute.lexically_normal();
  }
}

MapSaver::~MapSaver() {
  wait();
  if (thread_.joinable()) {
    thread_.request_stop();
    cv_.notify_all();
    thread_.join();
  }
}

bool MapSaver::start(const float* xyz, std::size_t points, std::int64_t snapshot_unix_ns) {
  if (pending_) return false;
  if (!thread_.joinable()) {
    thread_ = std::jthread([this](const std::stop_token& stop) { run(stop); });
  }
  {
    const std::lock_guard lock(mutex_);
    job_ = Job{xyz, points, snapshot_unix_ns, next_number_++};
  }
  pending_ = true;
  cv_.notify_all();
  return true;
}

bool MapSaver::busy() const {
  return pending_;
}

std::optional<MapSaveOutcome> MapSaver::take_result() {
  if (!pending_) return std::nullopt;
  const std::lock_guard lock(mutex_);
  if (!result_) return std::nullopt;
  std::optional<MapSaveOutcome> out = std::move(result_);
  result_.reset();
  pending_ = false;
  return out;
}

std::optional<MapSaveOutcome> MapSaver::wait() {
  if (!pending_) return std::nullopt;
  std::unique_lock lock(mutex_);
  cv_.wait(lock, [this] { return result_.has_value(); });
  std::optional<MapSaveOutcome> out = std::move(result_);
  result_.reset();
  pending_ = false;
  return out;
}

void MapSaver::run(const std::stop_token& stop) {
  pthread_setname_np(pthread_self(), "livod-mapsave");
  while (true) {
    Job job;
    {
      std::unique_lock lock(mutex_);
      if (!cv_.wait(lock, stop, [this] { return job_.has_value(); })) return;
      job = *job_;
      job_.reset();
    }
    if (options_.before_write) options_.before_write();
    MapSaveOutcome outcome = write(job.xyz, job.points, job.snapshot_unix_ns, job.number);
    {
      const std::lock_guard lock(mutex_);
      result_ = std::move(outcome);
    }
    cv_.notify_all();
    if (on_done_) on_done_();
  }
}

MapSaveOutcome MapSaver::write(const float* xyz, std::size_t points, std::int64_t snapshot_unix_ns,
                               int number) {
  const auto started = std::chrono::steady_clock::now();
  MapSaveOutcome out;
  out.points = points;
  out.save_number = number;
  out.snapshot_unix_ns = snapshot_unix_ns;
  const auto fail = [&](const std::string& what) {
    out.ok = false;
    out.error = what;
    out.path.clear();
    out.duration_s =
        std::chrono::duration<double>(std::chrono::steady_clock::now() - started).count();
    return out;
  };
  const std::filesystem::path& dir = options_.directory;
  std::error_code ec;
  if (options_.create_directory && !std::filesystem::is_directory(dir, ec)) {
    if (::mkdir(dir.c_str(), 0750) != 0 && errno != EEXIST) {
      return fail("cannot create the map folder " + dir.string() + ": " + errno_text(errno));
    }
  }
  if (!std::filesystem::is_directory(dir, ec)) {
    return fail("the map folder " + dir.string() + " does not exist");
  }
  std::filesystem::path path;
  if (options_.overwrite) {
    path = dir / "map.pcd";
  } else {
    const std::filesystem::path name = map_file_name(snapshot_unix_ns, number);
    path = dir / name;
    for (int k = 2; std::filesystem::exists(path, ec); ++k) {
      path = dir / (name.stem().string() + "-" + std::to_string(k) + ".pcd");
    }
  }
  std::filesystem::path partial = path;
  partial += ".partial";
  Fd fd(::open(partial.c_str(), O_WRONLY | O_CREAT | O_TRUNC | O_CLOEXEC, 0640));
  if (fd.get() < 0) return fail("cannot create " + partial.string() + ": " + errno_text(errno));
  const std::string header =
      io::pcd_header({{"x"}, {"y"}, {"z"}}, points, true, "livod map, world frame");
  // PCD binary data is the points' memory layout: little-endian float32 on every host livod
  // runs on.
  const bool written =
      write_all(fd.get(), header.data(), header.size()) &&
      write_all(fd.get(), reinterpret_cast<const char*>(xyz), points * 3 * sizeof(float)) &&
      ::fsync(fd.get()) == 0;
  const int write_errno = errno;
  if (!written || !fd.close()) {
    const int e = written ? errno : write_errno;
    std::filesystem::remove(partial, ec);
    return fail("cannot write " + path.string() + ": " + errno_text(e));
  }
  if (::rename(partial.c_str(), path.c_str()) != 0) {
    const int e = errno;
    std::filesystem::remove(partial, ec);
    return fail("cannot rename " + partial.string() + " to " + path.string() + ": " +
                errno_text(e));
  }
  // The rename itself is durable once the folder is synced.
  if (const int dfd = ::open(dir.c_str(), O_RDONLY | O_DIRECTORY | O_CLOEXEC); dfd >= 0) {
    ::fsync(dfd);
    ::close(dfd);
  }
  out.ok = true;
  out.path = path;
  out.bytes = header.size() + points * 3 * sizeof(float);
  out.duration_s =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - started).count();
  return out;
}

}  // namespace livod::daemon::runtime
