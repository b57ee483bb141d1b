// The bad-input suite (issue 14): the real `livod` binary on generated corrupt, truncated and
// hostile inputs, one case per defect class and subcommand. Every case asserts the exit status
// and that the output names the file and says what is wrong; cases that lose input must fail
// unless --accept-partial-input is given. Inputs are made from the shared test data and from
// `livod sim` (1 s), in a temp folder per test; nothing is written into the repository.

#include <gtest/gtest.h>
#include <sys/wait.h>

#include <array>
#include <cstdint>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <string>
#include <vector>

#include "tests/support/data_dir.hpp"

namespace livod::test {
namespace {

namespace fs = std::filesystem;

struct CliRun {
  int status = -1;
  std::string output;  // stdout and stderr
};

// Runs `livod ARGS` with a shell (ARGS are quoted by the caller where needed).
CliRun livod(const std::string& args) {
  const std::string command = std::string("'") + LIVOD_BINARY + "' " + args + " 2>&1";
  CliRun r;
  FILE* pipe = ::popen(command.c_str(), "r");
  if (pipe == nullptr) return r;
  std::array<char, 4096> buffer{};
  while (const std::size_t n = std::fread(buffer.data(), 1, buffer.size(), pipe)) {
    r.output.append(buffer.data(), n);
  }
  const int status = ::pclose(pipe);
  r.status = WIFEXITED(status) ? WEXITSTATUS(status) : 128 + WTERMSIG(status);
  return r;
}

std::string q(const fs::path& p) {
  return "'" + p.string() + "'";
}

// The exit status, and every needle in the output.
void expect_run(const CliRun& r, int status, const std::vector<std::string>& needles) {
  EXPECT_EQ(r.status, status) << r.output;
  for (const auto& n : needles) {
    EXPECT_NE(r.output.find(n), std::string::npos) << "missing '" << n << "' in:\n" << r.output;
  }
  // Sanitizer reports (ASan/UBSan CI) fail the case even when the status matches.
  EXPECT_EQ(r.output.find("runtime error:"), std::string::npos) << r.output;
  EXPECT_EQ(r.output.find("AddressSanitizer"), std::string::npos) << r.output;
}

std::string read_bytes(const fs::path& p) {
  std::ifstream in(p, std::ios::binary);
  return {std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>()};
}

void write_bytes(const fs::path& p, const std::string& bytes) {
  std::ofstream(p, std::ios::binary | std::ios::trunc) << bytes;
}

std::uint32_t le32(const std::string& b, std::size_t at) {
  std::uint32_t v = 0;
  std::memcpy(&v, b.data() + at, 4);
  return v;
}

// File offset of classic pcap record `index`.
std::size_t record_offset(const std::string& pcap, std::size_t index) {
  std::size_t at = 24;
  for (std::size_t i = 0; i < index; ++i) at += 16 + le32(pcap, at + 8);
  return at;
}

// A pcap whose record `index` has the capture length 0xFFFFFFFF.
std::size_t damage_pcap(const fs::path& in, const fs::path& out, std::size_t index) {
  std::string b = read_bytes(in);
  const std::size_t at = record_offset(b, index);
  std::memset(b.data() + at + 8, 0xFF, 4);
  write_bytes(out, b);
  return at;
}

// A 1 s street_vehicle_vlp16 simulation (VLP-16 pcap, SBG candump log, config.yaml) in `dir`.
fs::path simulate(const fs::path& dir) {
  const fs::path out = dir / "sim";
  const CliRun r =
      livod("sim --scenario street_vehicle_vlp16 --duration 1 --no-images -o " + q(out));
  EXPECT_EQ(r.status, 0) << r.output;
  return out;
}

fs::path ouster_config(const fs::path& dir, const std::string& extra_sensor_lines,
                       const std::string& model = "OS1-128",
                       const std::string& metadata = "ouster/pcaps/OS-1-128_v2.3.0_1024x10.json") {
  const fs::path path = dir / "ouster.yaml";
  std::ofstream(path)
      << "body_frame: os1.imu\nsensors:\n  - name: os1\n    driver: ouster\n    model: " << model
      << "\n    source:\n      replay:\n        file: "
      << data_path("ouster/pcaps/OS-1-128_v2.3.0_1024x10_lb_n3.pcap").string()
      << "\n    metadata: " << (metadata.front() == '/' ? metadata : data_path(metadata).string())
      << "\n    extrinsic: {translation: [0, 0, 0], rotation: {rpy_deg: [0, 0, 0]}}\n"
      << extra_sensor_lines;
  return path;
}

// ---------------------------------------------------------------------------------------------
// replay

TEST(BadInputReplay, CorruptPcapRecordIsReadPastReportedAndFails) {
  const fs::path dir = temp_dir("bad_replay_pcap");
  const fs::path sim = simulate(dir);
  const fs::path damaged = dir / "damaged.pcap";
  const std::size_t at = damage_pcap(sim / "vlp16.pcap", damaged, 300);
  const std::string base = "replay -q --config " + q(sim / "config.yaml") + " -o " +
                           q(dir / "out") + " vlp16=" + q(damaged);
  expect_run(livod(base), 3,
             {"input lost: " + damaged.string() + ": at byte offset " + std::to_string(at),
              "invalid packet capture length", "--accept-partial-input"});
  expect_run(livod(base + " --accept-partial-input"), 0,
             {damaged.string(), "partial input accepted"});
}

TEST(BadInputReplay, TruncatedPcapFails) {
  const fs::path dir = temp_dir("bad_replay_truncated");
  const fs::path sim = simulate(dir);
  const std::string whole = read_bytes(sim / "vlp16.pcap");
  const fs::path cut = dir / "cut.pcap";
  write_bytes(cut, whole.substr(0, whole.size() / 2 + 7));
  expect_run(livod("replay -q --config " + q(sim / "config.yaml") + " -o " + q(dir / "out") +
                   " vlp16=" + q(cut)),
             3, {"input lost: " + cut.string(), "the file ends in the damage"});
}

TEST(BadInputReplay, MalformedCandumpLinesAreReadPastAndFail) {
  const fs::path dir = temp_dir("bad_replay_candump");
  const fs::path sim = simulate(dir);
  std::string log = read_bytes(sim / "can_imu.log");
  const std::size_t line = log.find('\n', log.size() / 2) + 1;
  log.insert(line, "(garbage) can0 ZZZ#\n");
  const fs::path damaged = dir / "damaged.log";
  write_bytes(damaged, log);
  expect_run(
      livod("replay -q --config " + q(sim / "config.yaml") + " -o " + q(dir / "out") +
            " can_imu=" + q(damaged)),
      3,
      {"input lost: " + damaged.string() + ": at byte offset " + std::to_string(line), "1 lines"});
}

TEST(BadInputReplay, MapCellTooSmallForTheGridIsSaid) {
  const fs::path dir = temp_dir("bad_replay_map_cell");
  const fs::path sim = simulate(dir);
  expect_run(livod("replay -q --map-cell 1e-6 --config " + q(sim / "config.yaml") + " -o " +
                   q(dir / "out")),
             0, {"outside the map.pcd cell grid"});
  expect_run(livod("replay -q --map-max-points 10 --config " + q(sim / "config.yaml") + " -o " +
                   q(dir / "out2")),
             0, {"map.pcd reached its budget of 10 points", "covers only the first part"});
}

TEST(BadInputReplay, MalformedOusterMetadataIsRefusedBeforeReplaying) {
  const fs::path dir = temp_dir("bad_replay_metadata");
  const fs::path metadata = dir / "cut.json";
  write_bytes(metadata,
              read_bytes(data_path("ouster/pcaps/OS-1-128_v2.3.0_1024x10.json")).substr(0, 300));
  const fs::path config = ouster_config(dir, "", "OS1-128", metadata.string());
  expect_run(livod("replay -q --config " + q(config) + " -o " + q(dir / "out")), 1,
             {config.string() + ":3:1: error: sensors[0].metadata", metadata.string(), "JSON"});
}

TEST(BadInputReplay, MissingRecordingNamesTheFile) {
  const fs::path dir = temp_dir("bad_replay_missing");
  const fs::path sim = simulate(dir);
  expect_run(livod("replay -q --config " + q(sim / "config.yaml") + " -o " + q(dir / "out") +
                   " vlp16=" + q(dir / "nope.pcap")),
             1, {(dir / "nope.pcap").string()});
}

// An Ouster bag cut in the middle: the index is rebuilt by scanning, its only chunk (holding the
// metadata message) is cut, so nothing can be replayed: the message says why, and names no C++
// API.
TEST(BadInputReplay, TruncatedBagIsReindexedAndFails) {
  const fs::path dir = temp_dir("bad_replay_bag");
  const std::string whole = read_bytes(data_path("rosbag1/ouster_packets_512x10.bag"));
  const fs::path cut = dir / "cut.bag";
  write_bytes(cut, whole.substr(0, whole.size() * 3 / 4));
  const fs::path config = dir / "bag.yaml";
  std::ofstream(config) << "body_frame: os.imu\nsensors:\n  - name: os\n    driver: ouster\n"
                           "    source:\n      replay: {file: "
                        << cut.string()
                        << ", topic: /os_node0/lidar_packets}\n"
                           "    extrinsic: {translation: [0, 0, 0], rotation: {rpy_deg: [0, 0, "
                           "0]}}\n";
  const CliRun r = livod("replay -q --config " + q(config) + " -o " + q(dir / "out"));
  expect_run(r, 1,
             {cut.string() + ": topic /os_node0/metadata has no message (the bag is damaged: " +
                  cut.string() + ": at byte offset 4109",
              "runs past the end of the file"});
  EXPECT_EQ(r.output.find("Options::"), std::string::npos) << r.output;
}

// ---------------------------------------------------------------------------------------------
// check-config

TEST(BadInputCheckConfig, SyntaxErrorNamesFileAndLine) {
  const fs::path dir = temp_dir("bad_check_syntax");
  const fs::path config = dir / "broken.yaml";
  write_bytes(config, "sensors:\n  - name: [unclosed\n");
  expect_run(livod("check-config " + q(config)), 1, {config.string() + ":", "error"});
}

TEST(BadInputCheckConfig, ModelContradictingTheMetadata) {
  const fs::path dir = temp_dir("bad_check_model");
  const fs::path config = ouster_config(dir, "", "OS1-16");
  expect_run(livod("check-config " + q(config)), 1,
             {config.string() + ":3:1: error: sensors[0].metadata",
              "model OS1-16 contradicts the metadata, which describes an OS-1-128 (128 beams)"});
}

TEST(BadInputCheckConfig, OusterAzimuthFrameCutIsRefused) {
  const fs::path dir = temp_dir("bad_check_cut");
  const fs::path config = ouster_config(dir, "    frame_cut: {mode: azimuth}\n");
  expect_run(livod("check-config " + q(config)), 1,
             {config.string(), "sensors[0].frame_cut.mode", "use: frame_id"});
}

TEST(BadInputCheckConfig, MalformedMetadataIsRead) {
  const fs::path dir = temp_dir("bad_check_metadata");
  const fs::path metadata = dir / "bad.json";
  write_bytes(metadata, "{\"sensor_info\": 7}");
  const fs::path config = ouster_config(dir, "", "OS1-128", metadata.string());
  expect_run(livod("check-config " + q(config)), 1, {config.string(), metadata.string()});
}

// ---------------------------------------------------------------------------------------------
// decode

TEST(BadInputDecode, DamagedCaptureFailsUnlessAccepted) {
  const fs::path dir = temp_dir("bad_decode_damaged");
  const fs::path damaged = dir / "damaged.pcap";
  const std::size_t at =
      damage_pcap(data_path("velodyne/nebula_vlp16/velodyne_vlp16.pcap"), damaged, 40);
  const std::string base = "decode " + q(damaged) + " --model VLP-16 -o " + q(dir / "out.csv");
  expect_run(livod(base), 3,
             {"input lost: " + damaged.string() + ": at byte offset " + std::to_string(at)});
  expect_run(livod(base + " --accept-partial-input"), 0, {"partial input accepted"});
}

TEST(BadInputDecode, WrongPortModelOrMetadataDecodesNothingAndFails) {
  const fs::path dir = temp_dir("bad_decode_wrong");
  const fs::path capture = data_path("ouster/pcaps/OS-1-128_v2.3.0_1024x10_lb_n3.pcap");
  const std::string metadata = q(data_path("ouster/pcaps/OS-1-128_v2.3.0_1024x10.json"));
  const std::string out = " -o " + q(dir / "out.csv");
  expect_run(livod("decode " + q(capture) + " --model OS1-128 --metadata " + metadata +
                   " --port 9999" + out),
             1, {capture.string(), "nothing decoded", "7502 x192"});
  expect_run(livod("decode " + q(capture) + " --model VLP-16" + out), 1,
             {capture.string(), "nothing decoded"});
  expect_run(livod("decode " + q(capture) + " --model OS --metadata " +
                   q(data_path("ouster/pcaps/OS-1-32-G_v2.1.1_1024x10.json")) + out),
             1, {capture.string(), "decode errors"});
  expect_run(livod("decode " + q(capture) + " --model OS1-128 --metadata " + metadata + out), 0,
             {"scans 3"});
}

TEST(BadInputDecode, NotACaptureNamesTheFile) {
  const fs::path dir = temp_dir("bad_decode_garbage");
  const fs::path garbage = dir / "garbage.pcap";
  write_bytes(garbage, std::string(1000, 'x'));
  expect_run(livod("decode " + q(garbage) + " --model VLP-16 -o " + q(dir / "o.csv")), 1,
             {garbage.string(), "not a readable pcap"});
}

// ---------------------------------------------------------------------------------------------
// inspect

TEST(BadInputInspect, EmptyAndUnknownFiles) {
  const fs::path dir = temp_dir("bad_inspect");
  const fs::path empty = dir / "empty.pcap";
  write_bytes(empty, "");
  expect_run(livod("inspect " + q(empty)), 1, {empty.string() + ": empty file"});
  const fs::path unknown = dir / "unknown.bin";
  write_bytes(unknown, std::string(100, '\x07'));
  expect_run(livod("inspect " + q(unknown)), 1, {unknown.string(), "unrecognised file type"});
}

TEST(BadInputInspect, DamagedCaptureListsWhatWasLost) {
  const fs::path dir = temp_dir("bad_inspect_damaged");
  const fs::path damaged = dir / "damaged.pcap";
  const std::size_t at =
      damage_pcap(data_path("velodyne/nebula_vlp16/velodyne_vlp16.pcap"), damaged, 10);
  expect_run(livod("inspect " + q(damaged)), 0,
             {"lost        " + damaged.string() + ": at byte offset " + std::to_string(at)});
}

// ---------------------------------------------------------------------------------------------
// sim

TEST(BadInputSim, DurationsThatAreNotFinitePositiveAndBoundedAreRefused) {
  const fs::path dir = temp_dir("bad_sim");
  for (const char* d : {"inf", "nan", "-1", "0", "1e9"}) {
    expect_run(livod(std::string("sim --scenario street_vehicle_vlp16 --duration ") + d + " -o " +
                     q(dir / "out")),
               2, {"--duration", "must be a number of seconds in (0, 3600]"});
  }
  const fs::path scenario = dir / "nan.yaml";
  write_bytes(scenario, "base: street_vehicle_vlp16\nduration_s: .nan\n");
  expect_run(livod("sim --scenario-file " + q(scenario) + " -o " + q(dir / "out")), 1,
             {scenario.string(), "scenario.duration_s"});
}

// ---------------------------------------------------------------------------------------------
// eval

std::string tum_walk(int poses) {
  std::string text;
  for (int i = 0; i < poses; ++i) {
    text += std::to_string(10.0 + 0.1 * i) + " " + std::to_string(0.5 * i) + " " +
            std::to_string(0.01 * i * i) + " 0 0 0 0 1\n";
  }
  return text;
}

TEST(BadInputEval, HostileTrajectories) {
  const fs::path dir = temp_dir("bad_eval");
  const fs::path gt = dir / "gt.txt";
  write_bytes(gt, tum_walk(30));
  const fs::path huge = dir / "huge.txt";
  write_bytes(huge, tum_walk(29) + "12.95 1e300 0 0 0 0 0 1\n");
  expect_run(livod("eval " + q(huge) + " " + q(gt)), 1, {huge.string(), "line 30", "1e7 m"});
  const fs::path two = dir / "two.txt";
  write_bytes(two, tum_walk(2));
  expect_run(livod("eval " + q(two) + " " + q(gt)), 1, {"at least 3"});
  const fs::path doubled = dir / "doubled.txt";
  write_bytes(doubled, tum_walk(30) + tum_walk(30));
  expect_run(livod("eval " + q(doubled) + " " + q(gt)), 1, {doubled.string(), "earlier than"});
  std::string repeated;
  for (int i = 0; i < 30; ++i) repeated += tum_walk(i + 1).substr(tum_walk(i).size());
  repeated += repeated.substr(repeated.rfind('\n', repeated.size() - 2) + 1);
  const fs::path repeat = dir / "repeat.txt";
  write_bytes(repeat, repeated);
  expect_run(livod("eval " + q(repeat) + " " + q(gt)), 0, {"warning", "repeats the timestamp"});
  expect_run(livod("eval " + q(gt) + " " + q(gt) + " --t-max-diff nan"), 105, {"not a finite"});
  expect_run(livod("eval " + q(gt) + " " + q(gt) + " --t-offset nan"), 105, {"not a finite"});
  expect_run(livod("eval /dev/zero " + q(gt)), 1, {"/dev/zero", "not a text file"});
}

// ---------------------------------------------------------------------------------------------
// the command line itself

TEST(BadInputCommandLine, UnknownSubcommandIsNamed) {
  expect_run(livod("repaly"), 2, {"unknown subcommand 'repaly'", "did you mean 'replay'"});
}

}  // namespace
}  // namespace livod::test
