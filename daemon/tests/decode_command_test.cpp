// `livod decode` end to end on a real capture: exit codes, CSV and PCD contents.

#include <gtest/gtest.h>

#include <CLI/CLI.hpp>
#include <cstring>
#include <fstream>
#include <iterator>
#include <map>
#include <set>
#include <sstream>
#include <string>
#include <vector>

#include "daemon/commands/command.hpp"
#include "tests/support/data_dir.hpp"

namespace livod::daemon {
namespace {

int run(std::vector<std::string> args) {
  CLI::App app;
  CommandContext ctx;
  add_decode_command(app, ctx);
  args.insert(args.begin(), "decode");
  std::vector<const char*> argv{"livod"};
  for (const auto& a : args) argv.push_back(a.c_str());
  try {
    app.parse(static_cast<int>(argv.size()), argv.data());
  } catch (const CLI::ParseError& e) {
    return app.exit(e);
  }
  return ctx.exit_code;
}

const std::string kCapture = "velodyne/nebula_vlp16/velodyne_vlp16.pcap";

TEST(DecodeCommand, WritesEveryScanToCsv) {
  const auto out = livod::test::temp_dir("decode_csv") / "vlp16.csv";
  ASSERT_EQ(run({livod::test::data_path(kCapture).string(), "--model", "VLP-16", "--calibration",
                 livod::test::data_path("velodyne/nebula_vlp16/VLP16.yaml").string(), "-o",
                 out.string()}),
            0);
  std::ifstream in(out);
  std::string line;
  std::getline(in, line);
  EXPECT_EQ(line, "frame,x,y,z,intensity,t_ns,ring,return");
  std::set<int> frames;
  std::size_t rows = 0;
  std::int64_t first_t = 0;
  while (std::getline(in, line)) {
    std::istringstream fields(line);
    std::string frame, x, y, z, intensity, t;
    std::getline(fields, frame, ',');
    std::getline(fields, x, ',');
    std::getline(fields, y, ',');
    std::getline(fields, z, ',');
    std::getline(fields, intensity, ',');
    std::getline(fields, t, ',');
    frames.insert(std::stoi(frame));
    if (rows == 0) first_t = std::stoll(t);
    ++rows;
  }
  // 603 dual-return packets: a partial turn, three turns and a tail (see the velodyne tests).
  EXPECT_EQ(frames, (std::set<int>{0, 1, 2, 3, 4}));
  EXPECT_EQ(rows, 59414U);
  // t_ns is on the sensor timeline: this VLP-16 counts microseconds since its own (free-running)
  // top of the hour, 140.554572 s in the first packet; the §4.6 rule puts that in the hour of the
  // record time (01:27:51 UTC, 25 min away): 01:02:20.554572 UTC.
  EXPECT_EQ(first_t,
            1'673'398'800'000'000'000 + 140'554'572'000 + 2'304);  // laser 1 fires 2.304 us in
}

TEST(DecodeCommand, PcdAndUsageErrors) {
  const auto dir = livod::test::temp_dir("decode_pcd");
  const std::string capture = livod::test::data_path(kCapture).string();
  ASSERT_EQ(run({capture, "--model", "vlp16", "-o", (dir / "a.pcd").string()}), 0);
  std::ifstream in(dir / "a.pcd", std::ios::binary);
  std::string line;
  std::size_t points = 0;
  while (std::getline(in, line) && line.rfind("DATA", 0) != 0) {
    if (line.rfind("POINTS", 0) == 0) points = std::stoul(line.substr(6));
  }
  EXPECT_EQ(points, 59414U);
  EXPECT_EQ(run({capture, "--model", "VLP-64", "-o", (dir / "b.csv").string()}), 2);
  EXPECT_EQ(run({capture, "--model", "VLP-16", "-o", (dir / "b.ply").string()}), 2);
  EXPECT_EQ(run({capture, "--model", "HDL-32E", "--calibration",
                 livod::test::data_path("velodyne/nebula_vlp16/VLP16.yaml").string(), "-o",
                 (dir / "c.csv").string()}),
            1);  // a 16-laser calibration for a 32-laser sensor
  // Only the position port: no data packets, no scans: a failure (issue 14), with a valid (empty)
  // file all the same.
  ASSERT_EQ(run({capture, "--model", "VLP-16", "--port", "8308", "-o", (dir / "d.csv").string()}),
            1);
  std::ifstream empty(dir / "d.csv");
  std::string header;
  std::string extra;
  std::getline(empty, header);
  EXPECT_EQ(header, "frame,x,y,z,intensity,t_ns,ring,return");
  EXPECT_FALSE(std::getline(empty, extra));
}

TEST(DecodeCommand, HesaiWithItsAngleFile) {
  const auto dir = livod::test::temp_dir("decode_hesai");
  const std::string capture = livod::test::data_path("hesai/hesai_xt32.pcap").string();
  const std::string angles = livod::test::data_path("hesai/PandarXT32.csv").string();
  // The angle correction file is required: no nominal table for a Hesai unit.
  EXPECT_EQ(run({capture, "--model", "PANDARXT32", "-o", (dir / "a.csv").string()}), 1);
  ASSERT_EQ(
      run({capture, "--model", "xt32", "--calibration", angles, "-o", (dir / "b.csv").string()}),
      0);
  std::ifstream in(dir / "b.csv");
  std::string line;
  std::getline(in, line);
  std::map<int, std::size_t> rows_per_frame;
  while (std::getline(in, line)) ++rows_per_frame[std::stoi(line.substr(0, line.find(',')))];
  // Five scans (a partial turn, three turns, a partial turn); the fourth is nebula's reference
  // scan (63021 points with the model's default range 0.05-120 m).
  ASSERT_EQ(rows_per_frame.size(), 5U);
  EXPECT_EQ(rows_per_frame[3], 63021U);
}

}  // namespace
}  // namespace livod::daemon

// Issue 14: a decode that yields nothing, or that lost part of its capture, is not a success.
namespace livod::daemon {
namespace {

const std::string kOusterCapture = "ouster/pcaps/OS-1-128_v2.3.0_1024x10_lb_n3.pcap";
const std::string kOusterMetadata = "ouster/pcaps/OS-1-128_v2.3.0_1024x10.json";

int decode_ouster(const std::string& model, const std::vector<std::string>& extra = {}) {
  std::vector<std::string> args = {livod::test::data_path(kOusterCapture).string(),
                                   "--model",
                                   model,
                                   "--metadata",
                                   livod::test::data_path(kOusterMetadata).string(),
                                   "-o",
                                   (livod::test::temp_dir("decode_ouster") / "os.csv").string()};
  args.insert(args.end(), extra.begin(), extra.end());
  return run(args);
}

TEST(DecodeCommand, OusterProductNamesAreAcceptedAndCheckedAgainstTheMetadata) {
  EXPECT_EQ(decode_ouster("OS1-128"), 0);
  EXPECT_EQ(decode_ouster("OS-1-128"), 0);
  EXPECT_EQ(decode_ouster("OS"), 0);
  EXPECT_EQ(decode_ouster("OS1-16"), 1);
  EXPECT_EQ(decode_ouster("OS0-128"), 1);
}

TEST(DecodeCommand, NothingDecodedIsAFailure) {
  EXPECT_EQ(decode_ouster("OS1-128", {"--port", "9999"}), 1);  // wrong port
  const auto out = livod::test::temp_dir("decode_wrong_model") / "x.csv";
  EXPECT_EQ(run({livod::test::data_path(kOusterCapture).string(), "--model", "VLP-16", "-o",
                 out.string()}),
            1);  // wrong model
  // Wrong metadata: another sensor's (32 beams, another packet size) gives only decode errors.
  EXPECT_EQ(run({livod::test::data_path(kOusterCapture).string(), "--model", "OS", "--metadata",
                 livod::test::data_path("ouster/pcaps/OS-1-32-G_v2.1.1_1024x10.json").string(),
                 "-o", out.string()}),
            1);
}

TEST(DecodeCommand, LostInputFailsUnlessAccepted) {
  const auto dir = livod::test::temp_dir("decode_damaged");
  std::ifstream in(livod::test::data_path(kCapture), std::ios::binary);
  std::string bytes((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  // Record 30's capture length becomes 0xFFFFFFFF (records follow the 24-byte file header).
  std::size_t at = 24;
  for (int i = 0; i < 30; ++i) {
    std::uint32_t caplen = 0;
    std::memcpy(&caplen, bytes.data() + at + 8, 4);
    at += 16 + caplen;
  }
  std::memset(bytes.data() + at + 8, 0xFF, 4);
  const auto damaged = dir / "damaged.pcap";
  std::ofstream(damaged, std::ios::binary) << bytes;
  const std::vector<std::string> base = {damaged.string(), "--model", "VLP-16", "-o",
                                         (dir / "out.csv").string()};
  EXPECT_EQ(run(base), 3);
  auto accepted = base;
  accepted.push_back("--accept-partial-input");
  EXPECT_EQ(run(accepted), 0);
}

}  // namespace
}  // namespace livod::daemon
