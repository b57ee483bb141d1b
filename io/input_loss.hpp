#pragma once
// What a reader could not use of a damaged recording: where the damage is, how much was skipped
// and why. Readers read past damage where the format allows it (pcap records, pcapng blocks, bag
// chunks, candump lines) and keep one InputLoss per damaged stretch, so that a command can say
// exactly what was lost and refuse to call a partial result complete (docs/bad-input.md).

#include <cstddef>
#include <cstdint>
#include <optional>
#include <string>
#include <vector>

namespace livod::io {

struct InputLoss {
  std::string file;                          // the recording (path or name given to the reader)
  std::optional<std::uint64_t> byte_offset;  // where the damaged stretch starts, when known
  std::uint64_t bytes = 0;    // bytes skipped (0 when not known, e.g. inside a compressed chunk)
  std::uint64_t records = 0;  // records skipped: pcap records, bag messages, log lines
  bool records_estimated = false;  // `records` is estimated from the average record size
  std::string unit = "records";    // what `records` counts ("records", "messages", "lines")
  std::optional<double> seconds;   // recording time spanned by the loss, when known
  std::string reason;              // what was wrong ("record capture length 4294967295 ...")
};

// One line: "FILE: at byte offset N: REASON; skipped B bytes, R records, T s of recording".
std::string format_loss(const InputLoss& loss);

// The losses of one reader: every stretch up to a cap (a file damaged everywhere must not grow
// the list without bound), and totals over all of them.
class InputLossLog {
 public:
  static constexpr std::size_t kMaxEntries = 64;

  void add(InputLoss loss);
  // Sets the time span of the last loss (known only once reading resumes after it).
  void set_last_seconds(double seconds);
  // Adds another reader's losses (entries up to the cap, totals all).
  void merge(const InputLossLog& other);

  [[nodiscard]] const std::vector<InputLoss>& entries() const { return entries_; }
  [[nodiscard]] bool empty() const { return count_ == 0; }
  [[nodiscard]] std::uint64_t count() const { return count_; }      // all, kept or not
  [[nodiscard]] std::uint64_t bytes() const { return bytes_; }      // all, kept or not
  [[nodiscard]] std::uint64_t records() const { return records_; }  // all, kept or not
  [[nodiscard]] double seconds() const { return seconds_; }         // the known spans
  [[nodiscard]] std::uint64_t not_listed() const { return count_ - entries_.size(); }

 private:
  std::vector<InputLoss> entries_;
  std::uint64_t count_ = 0;
  std::uint64_t bytes_ = 0;
  std::uint64_t records_ = 0;
  double seconds_ = 0.0;
  bool last_listed_ = false;
};

}  // namespace livod::io
