// Tests of the candump log reader/writer, including interoperability with the real can-utils
// programs (installed by scripts/install-deps.sh): log2long parses our files with can-utils' own
// parser, and log2asc + asc2log produce a log written by can-utils' own writer for us to read.
// (canplayer/candump need a CAN socket, which this machine does not have.)

#include <gtest/gtest.h>

#include <algorithm>
#include <cctype>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <random>
#include <sstream>
#include <stdexcept>
#include <string>
#include <vector>

#include "core/error.hpp"
#include "io/candump.hpp"
#include "tests/support/data_dir.hpp"

namespace livod::io {
namespace {

namespace fs = std::filesystem;

CanFrame parse_ok(std::string_view line) {
  CanFrame frame;
  const auto error = parse_candump_line(line, frame);
  EXPECT_FALSE(error.has_value()) << line << ": " << (error ? error->message : "");
  return frame;
}

std::vector<std::uint8_t> bytes_of(const CanFrame& f) {
  return {f.data.begin(), f.data.begin() + f.len};
}

std::string read_text(const fs::path& path) {
  std::ifstream in(path, std::ios::binary);
  std::stringstream ss;
  ss << in.rdbuf();
  return ss.str();
}

std::vector<CanFrame> read_all(CandumpReader& reader) {
  std::vector<CanFrame> out;
  CanFrame frame;
  while (reader.next(frame)) out.push_back(frame);
  return out;
}

// Runs a shell command line; fails the test if it does not exit with 0.
void run(const std::string& command) {
  const int status = std::system(command.c_str());
  ASSERT_EQ(status, 0) << command;
}

// ---------------------------------------------------------------------------------------------
// Parsing

TEST(Candump, ParsesEveryFrameKind) {
  {
    const auto f = parse_ok("(1436509052.249713) can0 123#DEADBEEF");
    EXPECT_EQ(f.time_ns, 1436509052'249713000);
    EXPECT_EQ(f.interface, "can0");
    EXPECT_EQ(f.id, 0x123u);
    EXPECT_FALSE(f.extended || f.rtr || f.fd || f.error);
    EXPECT_EQ(bytes_of(f), (std::vector<std::uint8_t>{0xDE, 0xAD, 0xBE, 0xEF}));
  }
  {
    const auto f = parse_ok("(0000000001.000001) vcan12 1FFFFFFF#00.11.22.33.44.55.66.77");
    EXPECT_EQ(f.time_ns, 1'000'001'000);
    EXPECT_TRUE(f.extended);
    EXPECT_EQ(f.id, 0x1FFFFFFFu);
    EXPECT_EQ(f.len, 8);
    EXPECT_EQ(f.data[7], 0x77);
  }
  {
    const auto f = parse_ok("(1.000000) can0 00000123#");  // extended id, no data
    EXPECT_TRUE(f.extended);
    EXPECT_EQ(f.id, 0x123u);
    EXPECT_EQ(f.len, 0);
  }
  {
    const auto f = parse_ok("(1.000000) can0 7FF#R");
    EXPECT_TRUE(f.rtr);
    EXPECT_EQ(f.len, 0);
    const auto g = parse_ok("(1.000000) can0 7ff#r8");
    EXPECT_TRUE(g.rtr);
    EXPECT_EQ(g.len, 8);
    EXPECT_EQ(g.id, 0x7FFu);
  }
  {
    const auto f = parse_ok("(1.000000) can1 123##3" + std::string(128, 'a'));
    EXPECT_TRUE(f.fd);
    EXPECT_EQ(f.fd_flags, 3);
    EXPECT_EQ(f.len, 64);
    EXPECT_EQ(f.data[63], 0xAA);
    const auto g = parse_ok("(1.000000) can1 12345678##0");
    EXPECT_TRUE(g.fd && g.extended);
    EXPECT_EQ(g.len, 0);
  }
  {
    const auto f = parse_ok("(1.000000) can0 20000080#0000000000000000");
    EXPECT_TRUE(f.error);
    EXPECT_FALSE(f.extended);
    EXPECT_EQ(f.id, 0x80u);  // CAN_ERR_BUSERROR
    EXPECT_EQ(f.len, 8);
  }
  {
    const auto f = parse_ok("(1.000000) can0 123#1122334455667788_E");
    EXPECT_EQ(f.len, 8);
    EXPECT_EQ(f.len8_dlc, 14);
  }
  {
    // candump -x direction flag, right-aligned interface, trailing CR, nanosecond fraction.
    const auto f = parse_ok("(1436509052.123456789)  can0 123#DEADBEEF T\r");
    EXPECT_EQ(f.direction, 'T');
    EXPECT_EQ(f.time_ns, 1436509052'123456789);
    EXPECT_EQ(f.interface, "can0");
  }
}

struct BadLine {
  std::string line;
  std::size_t column;
  std::string message_part;
};

TEST(Candump, RejectsMalformedLinesWithTheirColumn) {
  const std::vector<BadLine> bad = {
      {"1436509052.249713 can0 123#00", 0, "'('"},
      {"(1436509052.24971) can0 123#00", 12, "fractional"},
      {"(1436509052.2497130) can0 123#00", 12, "fractional"},
      {"(1436509052.2497130000) can0 123#00", 21, "')'"},
      {"(.249713) can0 123#00", 1, "seconds"},
      {"(99999999999.000000) can0 123#00", 11, "too large"},
      {"(1436509052.249713)can0 123#00", 19, "space"},
      {"(1436509052.249713) can0", 24, "space after the interface"},
      {"(1436509052.249713) can0 ", 24, "space after the interface"},
      {"(1436509052.249713) abcdefghijklmnop 123#00", 20, "15 bytes"},
      {"(1436509052.249713) can0 1234#00", 25, "3 or 8"},
      {"(1436509052.249713) can0 123", 25, "3 or 8"},
      {"(1436509052.249713) can0 12G#00", 27, "hex digit in CAN id"},
      {"(1436509052.249713) can0 800#00", 25, "above 0x7FF"},
      {"(1436509052.249713) can0 40000000#00", 25, "above 0x1FFFFFFF"},
      {"(1436509052.249713) can0 A0000001#00", 25, "flag bits"},
      {"(1436509052.249713) can0 123#0", 29, "odd number"},
      {"(1436509052.249713) can0 123#0G", 30, "invalid hex digit"},
      {"(1436509052.249713) can0 123#001122334455667788", 45, "more than 8"},
      {"(1436509052.249713) can0 123##", 30, "flags"},
      {"(1436509052.249713) can0 123##0" + std::string(130, '0'), 159, "more than 64"},
      {"(1436509052.249713) can0 123#R9", 30, "DLC digit"},
      {"(1436509052.249713) can0 123#R11", 30, "DLC digit"},
      {"(1436509052.249713) can0 20000001#R", 34, "error frame"},
      {"(1436509052.249713) can0 20000001##0", 34, "classic"},
      {"(1436509052.249713) can0 123#11223344556677_E", 43, "'_'"},
      {"(1436509052.249713) can0 123#1122334455667788_8", 45, "'_'"},
      {"(1436509052.249713) can0 123#00 X", 32, "direction"},
      {"(1436509052.249713) can0 123#00 R R", 32, "direction"},
      {"(1436509052.249713) can\x01 123#00", 23, "invalid character"},
  };
  for (const auto& b : bad) {
    CanFrame frame;
    const auto error = parse_candump_line(b.line, frame);
    ASSERT_TRUE(error.has_value()) << b.line;
    EXPECT_EQ(error->column, b.column) << b.line << ": " << error->message;
    EXPECT_NE(error->message.find(b.message_part), std::string::npos)
        << b.line << ": " << error->message;
  }
}

TEST(Candump, ReaderReportsLineAndByteOffset) {
  const std::string text =
      "(1436509052.249713) can0 123#DEADBEEF\n"
      "\n"
      "(1436509052.349713) can0 123#DEADBEE\n"
      "(1436509052.449713) can0 124#00\n";
  auto reader = CandumpReader::from_memory(text, "bus.log");
  CanFrame frame;
  ASSERT_TRUE(reader.next(frame));
  EXPECT_EQ(frame.id, 0x123u);
  try {
    reader.next(frame);
    FAIL() << "malformed line accepted";
  } catch (const FormatError& e) {
    // Line 3 starts at byte 39; the odd digit is at column 35 of that line.
    EXPECT_EQ(e.offset(), 39u + 35u);
    const std::string what = e.what();
    EXPECT_NE(what.find("bus.log"), std::string::npos) << what;
    EXPECT_NE(what.find("line 3, column 36"), std::string::npos) << what;
    EXPECT_NE(what.find("odd number"), std::string::npos) << what;
  }
}

TEST(Candump, LenientModeSkipsAndCounts) {
  const std::string text =
      "(1.000000) can0 123#00\n"
      "garbage line\n" +
      std::string(5000, 'x') +
      "\n(2.000000) can0 124#01\r\n"
      "(3.000000) can0 125#R\n"
      "   \n"
      "(4.000000) can0 126#02";  // no final newline
  auto reader = CandumpReader::from_memory(text, "mixed.log", {.lenient = true});
  const auto frames = read_all(reader);
  ASSERT_EQ(frames.size(), 4u);
  EXPECT_EQ(frames[1].id, 0x124u);
  EXPECT_EQ(frames[1].data[0], 0x01);
  EXPECT_EQ(frames[3].id, 0x126u);
  EXPECT_EQ(frames[3].time_ns, 4'000'000'000);
  EXPECT_EQ(reader.stats().frames, 4u);
  EXPECT_EQ(reader.stats().skipped, 2u);
  EXPECT_EQ(reader.stats().lines, 7u);
  EXPECT_NE(reader.first_skipped_error().find("line 2"), std::string::npos)
      << reader.first_skipped_error();
  // The two consecutive bad lines are one loss, spanning the second between their neighbours.
  ASSERT_EQ(reader.losses().count(), 1u);
  const InputLoss& loss = reader.losses().entries()[0];
  EXPECT_EQ(loss.file, "mixed.log");
  EXPECT_EQ(loss.byte_offset, 23u);
  EXPECT_EQ(loss.bytes, 13u + 5001u);
  EXPECT_EQ(loss.records, 2u);
  EXPECT_EQ(loss.unit, "lines");
  ASSERT_TRUE(loss.seconds.has_value());
  EXPECT_DOUBLE_EQ(*loss.seconds, 1.0);
  EXPECT_NE(loss.reason.find("line 2"), std::string::npos) << loss.reason;

  // A bad last line is a loss that ends the file.
  auto tail =
      CandumpReader::from_memory("(1.000000) can0 123#00\n(2.0000", "tail.log", {.lenient = true});
  read_all(tail);
  ASSERT_EQ(tail.losses().count(), 1u);
  EXPECT_FALSE(tail.losses().entries()[0].seconds.has_value());

  // Strict mode throws on an over-long line.
  const std::string strict_text = "(1.000000) can0 123#00\n" + std::string(5000, 'x') + "\n";
  auto strict = CandumpReader::from_memory(strict_text, "long.log");
  CanFrame frame;
  ASSERT_TRUE(strict.next(frame));
  EXPECT_THROW(strict.next(frame), FormatError);
}

TEST(Candump, MissingFileThrows) {
  EXPECT_THROW(CandumpReader("/nonexistent/dir/x.log"), Error);
  EXPECT_THROW(CandumpWriter("/nonexistent/dir/x.log"), Error);
}

// ---------------------------------------------------------------------------------------------
// Writing and round trips

std::vector<CanFrame> sample_frames(std::size_t count, bool with_errors_and_raw_dlc,
                                    std::uint32_t seed) {
  std::mt19937 rng(seed);
  const std::vector<std::uint8_t> fd_lengths = {0, 1, 5, 8, 12, 16, 20, 24, 32, 48, 64};
  const std::vector<std::string> interfaces = {"can0", "can1", "vcan0"};
  std::vector<CanFrame> frames;
  std::int64_t t = 1436509052'249713000;
  for (std::size_t i = 0; i < count; ++i) {
    CanFrame f;
    t += 1000 * static_cast<std::int64_t>(1 + rng() % 5000);
    f.time_ns = t;
    f.interface = interfaces[rng() % interfaces.size()];
    const unsigned kind = rng() % (with_errors_and_raw_dlc ? 7 : 5);
    f.extended = rng() % 2 == 0;
    f.id = f.extended ? rng() & 0x1FFFFFFF : rng() & 0x7FF;
    switch (kind) {
      case 0:
      case 1:  // classic data
        f.len = static_cast<std::uint8_t>(rng() % 9);
        break;
      case 2:  // remote request
        f.rtr = true;
        f.len = static_cast<std::uint8_t>(rng() % 9);
        break;
      case 3:
      case 4:  // CAN FD
        f.fd = true;
        f.fd_flags = static_cast<std::uint8_t>(rng() % 4);
        f.len = fd_lengths[rng() % fd_lengths.size()];
        break;
      case 5:  // error frame
        f.error = true;
        f.extended = false;
        f.id = 1U << (rng() % 9);
        f.len = 8;
        break;
      default:  // 8 bytes with a raw DLC
        f.len = 8;
        f.len8_dlc = static_cast<std::uint8_t>(9 + rng() % 7);
        break;
    }
    if (!f.rtr) {
      for (std::size_t b = 0; b < f.len; ++b) f.data[b] = static_cast<std::uint8_t>(rng());
    }
    frames.push_back(f);
  }
  return frames;
}

TEST(Candump, FormatsExactlyLikeCandump) {
  CanFrame f;
  f.time_ns = 1436509052'249713999;  // sub-microsecond part is truncated
  f.interface = "can0";
  f.id = 0x123;
  f.len = 4;
  f.data = {0xDE, 0xAD, 0xBE, 0xEF};
  EXPECT_EQ(format_candump_line(f), "(1436509052.249713) can0 123#DEADBEEF");
  f.time_ns = 5'000'001'000;
  f.extended = true;
  f.id = 0xABC;
  EXPECT_EQ(format_candump_line(f), "(0000000005.000001) can0 00000ABC#DEADBEEF");
  f.extended = false;
  f.id = 0x1BC;
  f.rtr = true;
  f.len = 3;
  EXPECT_EQ(format_candump_line(f), "(0000000005.000001) can0 1BC#R3");
  f.rtr = false;
  f.fd = true;
  f.fd_flags = 1;
  f.len = 2;
  f.direction = 'R';
  EXPECT_EQ(format_candump_line(f), "(0000000005.000001) can0 1BC##1DEAD R");

  CanFrame bad = f;
  bad.id = 0x800;
  EXPECT_THROW(format_candump_line(bad), std::invalid_argument);
  bad = f;
  bad.interface = "can 0";
  EXPECT_THROW(format_candump_line(bad), std::invalid_argument);
  bad = f;
  bad.len = 65;
  EXPECT_THROW(format_candump_line(bad), std::invalid_argument);
  bad = f;
  bad.fd = false;  // classic with fd_flags set and 2 bytes: flags invalid
  EXPECT_THROW(format_candump_line(bad), std::invalid_argument);
  bad = f;
  bad.rtr = true;  // RTR on FD
  EXPECT_THROW(format_candump_line(bad), std::invalid_argument);
  bad = f;
  bad.time_ns = -1;
  EXPECT_THROW(format_candump_line(bad), std::invalid_argument);
}

TEST(Candump, WriterReaderRoundTrip) {
  const auto dir = test::temp_dir("candump-roundtrip");
  const auto frames = sample_frames(2000, true, 1);
  {
    CandumpWriter writer(dir / "bus.log");
    for (const auto& f : frames) writer.write(f);
    writer.flush();
  }
  CandumpReader reader(dir / "bus.log");
  EXPECT_EQ(read_all(reader), frames);
  EXPECT_EQ(reader.stats().frames, frames.size());
  EXPECT_EQ(reader.stats().skipped, 0u);
}

// ---------------------------------------------------------------------------------------------
// can-utils interoperability

// Parses one line of can-utils' log2long output, e.g.
//   (1436509052.249713)  can0       123   [4]  DE AD BE EF               '....'
//   (1436509052.449713)  can0       123   [5]  remote request
//   (1436509052.549713)  can1       7FF  [12]  00 01 02 ...           (CAN FD: two-digit length)
//   (1436509052.649713)  can0  20000080   [8]  00 00 ... ERRORFRAME
struct LongLine {
  std::string stamp, interface, id;
  int len = -1;
  bool fd = false, rtr = false;
  std::vector<std::uint8_t> data;
};

LongLine parse_long(const std::string& line) {
  LongLine out;
  std::istringstream in(line);
  std::string len_token;
  in >> out.stamp >> out.interface >> out.id >> len_token;
  out.fd = len_token.size() == 4;  // "[NN]" for CAN FD, "[N]" for classic
  out.len = std::stoi(len_token.substr(1, len_token.size() - 2));
  std::string token;
  while (in >> token) {
    if (token == "remote") {
      out.rtr = true;
      break;
    }
    if (token.size() != 2 || !std::isxdigit(static_cast<unsigned char>(token[0])) ||
        !std::isxdigit(static_cast<unsigned char>(token[1])) ||
        static_cast<int>(out.data.size()) == out.len) {
      break;  // the ASCII column or ERRORFRAME
    }
    out.data.push_back(static_cast<std::uint8_t>(std::stoi(token, nullptr, 16)));
  }
  return out;
}

TEST(Candump, CanUtilsParsesOurLogs) {
  const auto dir = test::temp_dir("candump-log2long");
  const auto frames = sample_frames(500, true, 2);
  {
    CandumpWriter writer(dir / "ours.log");
    for (const auto& f : frames) writer.write(f);
  }
  run("log2long < '" + (dir / "ours.log").string() + "' > '" + (dir / "long.txt").string() + "'");
  std::istringstream long_text(read_text(dir / "long.txt"));
  std::string line;
  std::size_t i = 0;
  while (std::getline(long_text, line)) {
    if (line.empty() || line[0] != '(') continue;  // error-frame detail lines start with a tab
    ASSERT_LT(i, frames.size());
    const auto& f = frames[i];
    const auto parsed = parse_long(line);
    const std::string ours = format_candump_line(f);
    EXPECT_EQ(parsed.stamp, ours.substr(0, ours.find(')') + 1)) << ours;
    EXPECT_EQ(parsed.interface, f.interface) << ours;
    const std::uint32_t id = std::stoul(parsed.id, nullptr, 16);
    EXPECT_EQ(id, f.error ? (f.id | 0x20000000U) : f.id) << ours;
    EXPECT_EQ(parsed.id.size(), f.extended || f.error ? 8u : 3u) << ours;
    EXPECT_EQ(parsed.fd, f.fd) << ours;
    EXPECT_EQ(parsed.rtr, f.rtr) << ours;
    EXPECT_EQ(parsed.len, f.len) << ours;
    if (!f.rtr) {
      EXPECT_EQ(parsed.data, bytes_of(f)) << ours;
    }
    ++i;
  }
  EXPECT_EQ(i, frames.size());
}

TEST(Candump, WeReadLogsWrittenByCanUtils) {
  // Our log -> log2asc (Vector ASC) -> asc2log (can-utils' log writer) -> our reader. ASC carries
  // no error-frame payload and no raw DLC, so those kinds are left out; asc2log names interfaces
  // after the ASC channel (can0 for channel 1, ...), appends the direction flag " R" and, with no
  // usable date in the ASC header, restarts the clock: compare time differences.
  const auto dir = test::temp_dir("candump-asc");
  const auto frames = sample_frames(500, false, 3);
  {
    CandumpWriter writer(dir / "ours.log");
    for (const auto& f : frames) writer.write(f);
  }
  const std::string ours = (dir / "ours.log").string();
  const std::string asc = (dir / "bus.asc").string();
  const std::string back = (dir / "back.log").string();
  run("log2asc -I '" + ours + "' -O '" + asc + "' can0 can1 vcan0");
  run("asc2log -I '" + asc + "' -O '" + back + "' 2>/dev/null");

  CandumpReader reader(back);
  const auto theirs = read_all(reader);
  ASSERT_EQ(theirs.size(), frames.size());
  const std::vector<std::string> channel_names = {"can0", "can1", "vcan0"};
  for (std::size_t i = 0; i < frames.size(); ++i) {
    const auto& f = frames[i];
    const auto& g = theirs[i];
    const auto channel = static_cast<std::size_t>(
        std::find(channel_names.begin(), channel_names.end(), f.interface) - channel_names.begin());
    EXPECT_EQ(g.interface, "can" + std::to_string(channel)) << i;
    EXPECT_EQ(g.direction, 'R') << i;
    EXPECT_EQ(g.id, f.id) << i;
    EXPECT_EQ(g.extended, f.extended) << i;
    EXPECT_EQ(g.rtr, f.rtr) << i;
    EXPECT_EQ(g.fd, f.fd) << i;
    EXPECT_EQ(g.fd_flags, f.fd_flags) << i;
    EXPECT_EQ(g.len, f.len) << i;
    EXPECT_EQ(bytes_of(g), bytes_of(f)) << i;
    if (i > 0) {
      EXPECT_EQ(g.time_ns - theirs[i - 1].time_ns, f.time_ns - frames[i - 1].time_ns) << i;
    }
  }
}

}  // namespace
}  // namespace livod::io
