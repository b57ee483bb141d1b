#include "io/candump.hpp"

#include <array>
#include <cstdio>
#include <istream>
#include <limits>
#include <sstream>
#include <stdexcept>
#include <utility>

#include "core/error.hpp"
#include "core/time.hpp"

namespace livod::io {

namespace {

constexpr std::uint32_t kSffMax = 0x7FF;
constexpr std::uint32_t kEffMax = 0x1FFFFFFF;
constexpr std::uint32_t kErrFlag = 0x20000000;   // CAN_ERR_FLAG in struct can_frame's can_id
constexpr std::uint32_t kFlagBits = 0xE0000000;  // EFF | RTR | ERR
constexpr std::size_t kClassicMaxLen = 8;
constexpr std::size_t kFdMaxLen = 64;
constexpr std::size_t kMaxInterfaceName = 15;  // Linux IFNAMSIZ minus the terminating NUL
constexpr std::size_t kMaxSecondsDigits = 10;  // int64 ns overflows beyond year 2262 anyway
// Longest meaningful line: timestamp, interface, 8-digit id, "##F", 64 bytes with separators and
// a direction flag, with room to spare. Longer lines are errors (and bound memory for binary
// files given by mistake).
constexpr std::size_t kMaxLineBytes = 1024;

int hex_value(char c) {
  if (c >= '0' && c <= '9') return c - '0';
  if (c >= 'A' && c <= 'F') return c - 'A' + 10;
  if (c >= 'a' && c <= 'f') return c - 'a' + 10;
  return -1;
}

bool is_digit(char c) {
  return c >= '0' && c <= '9';
}

// Printable, non-space ASCII: what an interface name may contain.
bool is_name_char(char c) {
  return c > ' ' && c < 0x7F;
}

std::optional<CandumpParseError> fail(std::string message, std::size_t column) {
  return CandumpParseError{std::move(message), column};
}

// Parses "<id>#..." starting at line[pos]; `end` is the end of the frame token.
std::optional<CandumpParseError> parse_frame_token(std::string_view line, std::size_t pos,
                                                   std::size_t end, CanFrame& frame) {
  const std::size_t id_start = pos;
  std::size_t hash = id_start;
  while (hash < end && line[hash] != '#') ++hash;
  const std::size_t digits = hash - id_start;
  if (hash == end || (digits != 3 && digits != 8)) {
    return fail("CAN id must be 3 or 8 hex digits followed by '#'", id_start);
  }
  std::uint32_t value = 0;
  for (std::size_t i = id_start; i < hash; ++i) {
    const int v = hex_value(line[i]);
    if (v < 0) return fail("invalid hex digit in CAN id", i);
    value = (value << 4) | static_cast<std::uint32_t>(v);
  }
  if (digits == 3) {
    if (value > kSffMax) return fail("11-bit CAN id above 0x7FF", id_start);
    frame.id = value;
  } else if ((value & kErrFlag) != 0) {
    if ((value & kFlagBits) != kErrFlag) {
      return fail("error frame id with EFF/RTR flag bits set", id_start);
    }
    frame.error = true;
    frame.id = value & kEffMax;
  } else {
    if (value > kEffMax) return fail("29-bit CAN id above 0x1FFFFFFF", id_start);
    frame.extended = true;
    frame.id = value;
  }

  pos = hash + 1;
  if (pos < end && (line[pos] == 'R' || line[pos] == 'r')) {
    if (frame.error) return fail("remote request on an error frame", pos);
    frame.rtr = true;
    ++pos;
    if (pos < end) {
      const int dlc = hex_value(line[pos]);
      if (dlc < 0 || dlc > static_cast<int>(kClassicMaxLen) || pos + 1 != end) {
        return fail("remote request takes at most one DLC digit 0-8", pos);
      }
      frame.len = static_cast<std::uint8_t>(dlc);
    }
    return std::nullopt;
  }

  std::size_t max_len = kClassicMaxLen;
  if (pos < end && line[pos] == '#') {
    if (frame.error) return fail("error frames are classic CAN frames", pos);
    frame.fd = true;
    max_len = kFdMaxLen;
    ++pos;
    const int flags = pos < end ? hex_value(line[pos]) : -1;
    if (flags < 0) return fail("CAN FD frame needs one hex flags digit after '##'", pos);
    frame.fd_flags = static_cast<std::uint8_t>(flags);
    ++pos;
  }

  std::size_t len = 0;
  while (pos < end) {
    if (line[pos] == '.') ++pos;  // optional separator before each byte
    if (pos >= end) break;
    if (line[pos] == '_') break;
    if (len == max_len) {
      return fail(frame.fd ? "more than 64 data bytes" : "more than 8 data bytes", pos);
    }
    const int high = hex_value(line[pos]);
    const int low = pos + 1 < end ? hex_value(line[pos + 1]) : -1;
    if (high < 0) return fail("invalid hex digit in data", pos);
    if (low < 0) {
      return fail(pos + 1 < end ? "invalid hex digit in data" : "odd number of hex digits in data",
                  pos + 1 < end ? pos + 1 : pos);
    }
    frame.data[len++] = static_cast<std::uint8_t>((high << 4) | low);
    pos += 2;
  }
  frame.len = static_cast<std::uint8_t>(len);

  if (pos < end) {  // "_<dlc>": raw DLC 9..15 of a classic 8-byte frame (newer can-utils)
    const int dlc = pos + 1 < end ? hex_value(line[pos + 1]) : -1;
    if (frame.fd || frame.error || len != kClassicMaxLen || dlc <= 8 || pos + 2 != end) {
      return fail("'_' must be followed by one DLC digit 9-F on an 8-byte classic frame", pos);
    }
    frame.len8_dlc = static_cast<std::uint8_t>(dlc);
  }
  return std::nullopt;
}

char hex_digit(unsigned v) {
  return "0123456789ABCDEF"[v & 0xF];
}

void append_hex(std::string& out, std::uint32_t value, int digits) {
  for (int i = digits - 1; i >= 0; --i) out.push_back(hex_digit(value >> (4 * i)));
}

}  // namespace

std::optional<CandumpParseError> parse_candump_line(std::string_view line, CanFrame& frame) {
  while (!line.empty() && (line.back() == '\r' || line.back() == ' ' || line.back() == '\t')) {
    line.remove_suffix(1);
  }
  frame.time_ns = 0;
  frame.interface.clear();
  frame.id = 0;
  frame.extended = frame.rtr = frame.fd = frame.error = false;
  frame.fd_flags = 0;
  frame.len8_dlc = 0;
  frame.direction = 0;
  frame.len = 0;
  frame.data.fill(0);

  std::size_t pos = 0;
  if (line.empty() || line[0] != '(') return fail("expected '(' starting the timestamp", 0);
  ++pos;
  const std::size_t seconds_start = pos;
  std::int64_t seconds = 0;
  while (pos < line.size() && is_digit(line[pos])) {
    if (pos - seconds_start == kMaxSecondsDigits) return fail("timestamp seconds too large", pos);
    seconds = seconds * 10 + (line[pos] - '0');
    ++pos;
  }
  if (pos == seconds_start) return fail("expected timestamp seconds", pos);
  if (pos >= line.size() || line[pos] != '.') return fail("expected '.' in the timestamp", pos);
  ++pos;
  const std::size_t fraction_start = pos;
  std::int64_t fraction = 0;
  while (pos < line.size() && is_digit(line[pos]) && pos - fraction_start < 9) {
    fraction = fraction * 10 + (line[pos] - '0');
    ++pos;
  }
  const std::size_t fraction_digits = pos - fraction_start;
  if (fraction_digits != 6 && fraction_digits != 9) {
    return fail("timestamp needs 6 (microseconds) or 9 (nanoseconds) fractional digits",
                fraction_start);
  }
  if (pos >= line.size() || line[pos] != ')') return fail("expected ')' after the timestamp", pos);
  ++pos;
  const std::int64_t fraction_ns = fraction_digits == 6 ? fraction * 1000 : fraction;
  if (seconds > (std::numeric_limits<std::int64_t>::max() - fraction_ns) / kNsPerSecond) {
    return fail("timestamp does not fit in int64 nanoseconds", seconds_start);
  }
  frame.time_ns = seconds * kNsPerSecond + fraction_ns;

  auto skip_spaces = [&] {
    const std::size_t start = pos;
    while (pos < line.size() && (line[pos] == ' ' || line[pos] == '\t')) ++pos;
    return pos - start;
  };
  if (skip_spaces() == 0) return fail("expected a space after the timestamp", pos);
  const std::size_t name_start = pos;
  while (pos < line.size() && is_name_char(line[pos])) ++pos;
  if (pos == name_start) return fail("expected an interface name", pos);
  if (pos - name_start > kMaxInterfaceName) {
    return fail("interface name longer than 15 bytes", name_start);
  }
  if (pos < line.size() && line[pos] != ' ' && line[pos] != '\t') {
    return fail("invalid character in the interface name", pos);
  }
  frame.interface.assign(line.substr(name_start, pos - name_start));
  if (skip_spaces() == 0) return fail("expected a space after the interface name", pos);

  const std::size_t token_start = pos;
  while (pos < line.size() && line[pos] != ' ' && line[pos] != '\t') ++pos;
  if (auto error = parse_frame_token(line, token_start, pos, frame)) return error;

  if (skip_spaces() != 0 && pos < line.size()) {
    if ((line[pos] == 'R' || line[pos] == 'T') && pos + 1 == line.size()) {
      frame.direction = line[pos];
      return std::nullopt;
    }
    return fail("unexpected text after the frame (only a direction flag R or T may follow)", pos);
  }
  if (pos < line.size()) return fail("unexpected character after the frame", pos);
  return std::nullopt;
}

std::string format_candump_line(const CanFrame& frame) {
  if (frame.time_ns < 0) throw std::invalid_argument("candump: negative timestamp");
  if (frame.interface.empty() || frame.interface.size() > kMaxInterfaceName) {
    throw std::invalid_argument("candump: interface name must have 1 to 15 bytes");
  }
  for (char c : frame.interface) {
    if (!is_name_char(c)) {
      throw std::invalid_argument("candump: interface name with space or control character");
    }
  }
  const int kinds = int{frame.extended} + int{frame.error};
  if (kinds > 1 || (frame.error && (frame.rtr || frame.fd)) || (frame.rtr && frame.fd)) {
    throw std::invalid_argument("candump: at most one of extended/error, and RTR only classic");
  }
  const std::uint32_t id_max = frame.extended || frame.error ? kEffMax : kSffMax;
  if (frame.id > id_max) throw std::invalid_argument("candump: CAN id out of range");
  if (frame.len > (frame.fd ? kFdMaxLen : kClassicMaxLen)) {
    throw std::invalid_argument("candump: data length above the frame type's maximum");
  }
  if (frame.fd_flags > 0xF || (frame.fd_flags != 0 && !frame.fd)) {
    throw std::invalid_argument("candump: FD flags are one nibble on FD frames only");
  }
  const bool raw_dlc = frame.len8_dlc != 0;
  if (raw_dlc && (frame.len8_dlc < 9 || frame.len8_dlc > 15 || frame.len != kClassicMaxLen ||
                  frame.fd || frame.rtr || frame.error)) {
    throw std::invalid_argument("candump: len8_dlc 9-15 only on 8-byte classic data frames");
  }
  if (frame.direction != 0 && frame.direction != 'R' && frame.direction != 'T') {
    throw std::invalid_argument("candump: direction must be 'R', 'T' or 0");
  }

  std::string line;
  line.reserve(64 + 2 * frame.len);
  char stamp[48];
  const int n = std::snprintf(stamp, sizeof stamp, "(%010lld.%06lld) ",
                              static_cast<long long>(frame.time_ns / kNsPerSecond),
                              static_cast<long long>((frame.time_ns % kNsPerSecond) / 1000));
  line.append(stamp, static_cast<std::size_t>(n));
  line.append(frame.interface);
  line.push_back(' ');
  if (frame.error) {
    append_hex(line, frame.id | kErrFlag, 8);
  } else {
    append_hex(line, frame.id, frame.extended ? 8 : 3);
  }
  line.push_back('#');
  if (frame.rtr) {
    line.push_back('R');
    if (frame.len != 0) line.push_back(hex_digit(frame.len));
  } else {
    if (frame.fd) {
      line.push_back('#');
      line.push_back(hex_digit(frame.fd_flags));
    }
    for (std::size_t i = 0; i < frame.len; ++i) append_hex(line, frame.data[i], 2);
    if (raw_dlc) {
      line.push_back('_');
      line.push_back(hex_digit(frame.len8_dlc));
    }
  }
  if (frame.direction != 0) {
    line.push_back(' ');
    line.push_back(frame.direction);
  }
  return line;
}

// ------------------------------------------------------------------------------------------------

struct CandumpReader::Impl {
  std::string source;
  Options options;
  std::unique_ptr<std::istream> in;
  std::array<char, kMaxLineBytes + 1> buffer{};
  std::uint64_t offset = 0;  // byte offset of the next line
  std::uint64_t line_number = 0;
  CandumpStats stats;
  std::string first_skipped_error;
  // Lenient mode: consecutive skipped lines form one loss, closed by the next frame (which gives
  // the time it spans) or by the end of the file.
  InputLossLog losses;
  std::optional<InputLoss> open_loss;
  std::optional<std::int64_t> last_time_ns;

  void close_loss(std::optional<std::int64_t> resume_ns) {
    if (!open_loss) return;
    if (resume_ns && last_time_ns && *resume_ns >= *last_time_ns) {
      open_loss->seconds = static_cast<double>(*resume_ns - *last_time_ns) * 1e-9;
    }
    losses.add(std::move(*open_loss));
    open_loss.reset();
  }
};

CandumpReader::CandumpReader(std::unique_ptr<Impl> impl) : impl_(std::move(impl)) {}

CandumpReader::CandumpReader(const std::filesystem::path& path, Options options)
    : impl_(std::make_unique<Impl>()) {
  impl_->source = path.string();
  impl_->options = options;
  auto file = std::make_unique<std::ifstream>(path, std::ios::binary);
  if (!*file) throw Error(impl_->source + ": cannot open candump log");
  impl_->in = std::move(file);
}

CandumpReader CandumpReader::from_memory(std::string_view text, std::string name, Options options) {
  auto impl = std::make_unique<Impl>();
  impl->source = std::move(name);
  impl->options = options;
  impl->in = std::make_unique<std::istringstream>(std::string(text), std::ios::binary);
  return CandumpReader(std::move(impl));
}

CandumpReader::~CandumpReader() = default;
CandumpReader::CandumpReader(CandumpReader&&) noexcept = default;
CandumpReader& CandumpReader::operator=(CandumpReader&&) noexcept = default;

bool CandumpReader::next(CanFrame& frame) {
  Impl& s = *impl_;
  std::istream& in = *s.in;
  while (true) {
    in.getline(s.buffer.data(), static_cast<std::streamsize>(s.buffer.size()));
    const auto extracted = static_cast<std::uint64_t>(in.gcount());
    if (extracted == 0 && in.eof()) {
      s.close_loss(std::nullopt);
      return false;
    }
    const std::uint64_t line_offset = s.offset;
    ++s.line_number;
    ++s.stats.lines;
    std::optional<CandumpParseError> error;
    if (in.fail() && !in.eof()) {
      // No newline within kMaxLineBytes: skip the rest of the line so that lenient mode resumes.
      in.clear();
      in.ignore(std::numeric_limits<std::streamsize>::max(), '\n');
      s.offset += extracted + static_cast<std::uint64_t>(in.gcount());
      error = CandumpParseError{"line longer than " + std::to_string(kMaxLineBytes) + " bytes",
                                kMaxLineBytes};
    } else {
      s.offset += extracted;
      const bool had_newline = !in.eof();
      const std::string_view line(s.buffer.data(), extracted - (had_newline ? 1 : 0));
      if (line.find_first_not_of(" \t\r") == std::string_view::npos) continue;  // blank line
      error = parse_candump_line(line, frame);
      if (!error) {
        ++s.stats.frames;
        s.close_loss(frame.time_ns);
        s.last_time_ns = frame.time_ns;
        return true;
      }
    }
    const std::string message = "line " + std::to_string(s.line_number) + ", column " +
                                std::to_string(error->column + 1) + ": " + error->message;
    const FormatError format_error(s.source, line_offset + error->column, message);
    if (!s.options.lenient) throw format_error;
    ++s.stats.skipped;
    if (s.first_skipped_error.empty()) s.first_skipped_error = format_error.what();
    if (!s.open_loss) {
      s.open_loss.emplace();
      s.open_loss->file = s.source;
      s.open_loss->byte_offset = line_offset;
      s.open_loss->unit = "lines";
      s.open_loss->reason = message;
    }
    s.open_loss->bytes = s.offset - s.open_loss->byte_offset.value_or(line_offset);
    ++s.open_loss->records;
  }
}

const CandumpStats& CandumpReader::stats() const {
  return impl_->stats;
}

const std::string& CandumpReader::first_skipped_error() const {
  return impl_->first_skipped_error;
}

const InputLossLog& CandumpReader::losses() const {
  return impl_->losses;
}

// ------------------------------------------------------------------------------------------------

CandumpWriter::CandumpWriter(const std::filesystem::path& path)
    : source_(path.string()), out_(path, std::ios::binary | std::ios::trunc) {
  if (!out_) throw Error(source_ + ": cannot create candump log");
}

void CandumpWriter::write(const CanFrame& frame) {
  line_ = format_candump_line(frame);
  line_.push_back('\n');
  out_.write(line_.data(), static_cast<std::streamsize>(line_.size()));
}

void CandumpWriter::flush() {
  out_.flush();
  if (!out_) throw Error(source_ + ": writing the candump log failed");
}

}  // namespace livod::io
