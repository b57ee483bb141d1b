// Reproduces evo's stored results (shared/data/trajectory_eval/res_files/*.zip, written by
// evo_ape / evo_rpe / evo's rpe-for-each script on the files of shared/data/trajectory_eval).
// Expected numbers are read from the zips at run time: the options come from info.json (evo
// writes them into the title), the statistics from stats.json and the per-pose errors from the
// arrays. Tolerance 1e-4 m, on every statistic and on every element of the error arrays.

#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <iostream>
#include <map>
#include <nlohmann/json.hpp>
#include <set>
#include <string>
#include <vector>

#include "tests/support/data_dir.hpp"
#include "tools/eval/evaluate.hpp"
#include "tools/eval/tests/report_line.hpp"
#include "tools/eval/tests/zip_archive.hpp"

namespace livod::eval {
namespace {

constexpr double kTolerance = 1e-4;  // metres

// The result files this test reproduces, and those whose inputs are not in the shared data.
// EveryResultFileIsClassified fails if another file appears.
const std::set<std::string>& reproduced_res_files() {
  static const std::set<std::string> files = {"orb_ape.zip", "sptam_ape.zip", "orb_rpe.zip",
                                              "sptam_rpe.zip"};
  return files;
}

const std::set<std::string>& res_files_without_data() {
  static const std::set<std::string> files = {"orb_rpe-for-each.zip", "sptam_rpe-for-each.zip"};
  return files;
}

std::filesystem::path data_file(const std::string& name) {
  return test::data_path("trajectory_eval/" + name);
}

// evo stores arrays as .npy bytes named *.npz (older versions) or as real .npz archives.
std::vector<double> read_array(const test_support::ZipArchive& zip, const std::string& name) {
  const std::string bytes = zip.read(name);
  if (bytes.rfind("PK\x03\x04", 0) == 0) {
    const test_support::ZipArchive inner(bytes, name);
    return test_support::parse_npy_f8(inner.read(inner.entries().at(0).name), name);
  }
  return test_support::parse_npy_f8(bytes, name);
}

struct EvoRun {
  nlohmann::json info;
  nlohmann::json stats;
  test_support::ZipArchive zip;
};

EvoRun open_res_file(const std::string& name) {
  test_support::ZipArchive zip = test_support::ZipArchive::open(data_file("res_files/" + name));
  EvoRun run{nlohmann::json::parse(zip.read("info.json")),
             nlohmann::json::parse(zip.read("stats.json")), std::move(zip)};
  return run;
}

// Which data files and options an evo result used, recovered from info.json.
struct EvoOptions {
  std::string gt_file;
  std::string est_file;
  TrajectoryFormat format = TrajectoryFormat::kTum;
  Alignment alignment = Alignment::kNone;
  double delta = 0.0;
  DeltaUnit unit = DeltaUnit::kFrames;
};

Alignment alignment_from_title(const std::string& title) {
  if (title.find("SE(3) Umeyama") != std::string::npos) return Alignment::kSe3;
  if (title.find("Sim(3) Umeyama") != std::string::npos) return Alignment::kSim3;
  EXPECT_NE(title.find("not aligned"), std::string::npos) << "unknown alignment in: " << title;
  return Alignment::kNone;
}

TrajectoryFormat format_for(const std::string& gt_file) {
  if (gt_file.find("KITTI") != std::string::npos) return TrajectoryFormat::kKitti;
  if (gt_file.ends_with(".csv")) return TrajectoryFormat::kEuroc;
  return TrajectoryFormat::kTum;
}

EvoOptions options_from_info(const nlohmann::json& info) {
  EvoOptions o;
  const auto title = info.at("title").get<std::string>();
  o.gt_file = std::filesystem::path(info.at("ref_name").get<std::string>()).filename().string();
  o.est_file = std::filesystem::path(info.at("est_name").get<std::string>()).filename().string();
  o.format = format_for(o.gt_file);
  o.alignment = alignment_from_title(title);
  EXPECT_NE(title.find("w.r.t. translation part"), std::string::npos) << title;
  // RPE titles read "... for delta = 10.0 (m) using consecutive pairs ...".
  const std::string delta_key = "delta = ";
  if (const std::size_t at = title.find(delta_key); at != std::string::npos) {
    std::size_t used = 0;
    o.delta = std::stod(title.substr(at + delta_key.size()), &used);
    const std::size_t open = at + delta_key.size() + used + 1;
    const std::size_t close = title.find(')', open);
    EXPECT_EQ(title[open], '(') << title;
    const auto unit = parse_delta_unit(title.substr(open + 1, close - open - 1));
    EXPECT_TRUE(unit.has_value()) << title;
    o.unit = unit.value_or(DeltaUnit::kFrames);
    EXPECT_NE(title.find("using consecutive pairs"), std::string::npos) << title;
  }
  return o;
}

EvalResult run_livod(const EvoOptions& o) {
  EvalOptions options;
  options.format = o.format;
  options.alignment = o.alignment;
  if (o.delta > 0.0) {
    options.rpe_delta = o.delta;
    options.rpe_unit = o.unit;
  }
  return evaluate_files(data_file(o.est_file), data_file(o.gt_file), options);
}

void expect_statistics(const nlohmann::json& evo, const ErrorStatistics& ours,
                       const std::string& what) {
  const std::map<std::string, double> livod = {{"rmse", ours.rmse},     {"mean", ours.mean},
                                               {"median", ours.median}, {"std", ours.std},
                                               {"min", ours.min},       {"max", ours.max}};
  for (const auto& [key, value] : livod) {
    const double expected = evo.at(key).get<double>();
    EXPECT_NEAR(value, expected, kTolerance) << what << " " << key;
    std::cout << "  " << what << " " << key << ": evo " << expected << "  livod " << value
              << "  diff " << value - expected << "\n";
  }
  // The sum of squares grows with the count: compare it relative to its size.
  const double sse = evo.at("sse").get<double>();
  EXPECT_NEAR(ours.sse, sse, kTolerance * std::max(1.0, sse)) << what << " sse";
}

void expect_arrays_match(const std::vector<double>& evo, const std::vector<double>& ours,
                         const std::string& what) {
  ASSERT_EQ(ours.size(), evo.size()) << what;
  double worst = 0.0;
  for (std::size_t i = 0; i < evo.size(); ++i) {
    worst = std::max(worst, std::abs(ours[i] - evo[i]));
    ASSERT_NEAR(ours[i], evo[i], kTolerance) << what << " element " << i;
  }
  std::cout << "  " << what << ": " << evo.size() << " values, max |diff| " << worst << "\n";
}

void check_ape(const std::string& res_file) {
  SCOPED_TRACE(res_file);
  const EvoRun evo = open_res_file(res_file);
  const auto title = evo.info.at("title").get<std::string>();
  ASSERT_EQ(title.rfind("APE", 0), 0u) << title;
  const EvoOptions o = options_from_info(evo.info);
  const EvalResult r = run_livod(o);
  std::cout << res_file << " (" << o.est_file << " vs " << o.gt_file << ", align "
            << to_string(o.alignment) << ")\n";
  expect_statistics(evo.stats, r.ape, "APE");
  expect_arrays_match(read_array(evo.zip, "error_array.npz"), r.ape_m, "APE error_array");
}

void check_rpe(const std::string& res_file) {
  SCOPED_TRACE(res_file);
  const EvoRun evo = open_res_file(res_file);
  const auto title = evo.info.at("title").get<std::string>();
  ASSERT_EQ(title.rfind("RPE", 0), 0u) << title;
  const EvoOptions o = options_from_info(evo.info);
  ASSERT_GT(o.delta, 0.0) << "no delta in: " << title;
  const EvalResult r = run_livod(o);
  ASSERT_TRUE(r.rpe_translation.has_value());
  std::cout << res_file << " (" << o.est_file << " vs " << o.gt_file << ", delta " << o.delta << " "
            << to_string(o.unit) << ")\n";
  expect_statistics(evo.stats, *r.rpe_translation, "RPE");
  expect_arrays_match(read_array(evo.zip, "error_array.npz"), r.rpe.translation_m,
                      "RPE error_array");
}

// evo_rpe-for-each results: evo made them from ROS_example.bag (topics "groundtruth",
// "ORB-SLAM", "S-PTAM"; see evo's rpe-for-each demo), which is not part of the shared data, so
// they cannot be reproduced here. The test pins that reason down: if the inputs they name ever
// appear in the data folder, it fails and the files must be covered.
void expect_inputs_absent(const std::string& res_file) {
  SCOPED_TRACE(res_file);
  const EvoRun evo = open_res_file(res_file);
  const auto title = evo.info.at("title").get<std::string>();
  EXPECT_NE(title.find("mean RPE"), std::string::npos) << title;
  for (const char* key : {"est_name", "ref_name"}) {
    const auto name = evo.info.at(key).get<std::string>();
    EXPECT_FALSE(std::filesystem::exists(test::data_dir() / "trajectory_eval" / name)) << name;
    EXPECT_FALSE(std::filesystem::exists(test::data_dir() / "trajectory_eval" / (name + ".txt")))
        << name;
  }
}

TEST(EvoReproduction, EveryResultFileIsClassified) {
  std::set<std::string> present;
  for (const auto& entry : std::filesystem::directory_iterator(data_file("res_files"))) {
    present.insert(entry.path().filename().string());
  }
  std::set<std::string> known = reproduced_res_files();
  known.insert(res_files_without_data().begin(), res_files_without_data().end());
  EXPECT_EQ(present, known);
}

TEST(EvoReproduction, ApeKitti00OrbSe3) {
  check_ape("orb_ape.zip");
}
TEST(EvoReproduction, ApeKitti00SptamSe3) {
  check_ape("sptam_ape.zip");
}
TEST(EvoReproduction, RpeKitti00Orb10m) {
  check_rpe("orb_rpe.zip");
}
TEST(EvoReproduction, RpeKitti00Sptam10m) {
  check_rpe("sptam_rpe.zip");
}
TEST(EvoReproduction, RpeForEachResultsComeFromABagThatIsNotInTheData) {
  for (const std::string& f : res_files_without_data()) expect_inputs_absent(f);
}

TEST(EvoReproduction, ReportPrintsTheAteRmseInMetres) {
  const EvoRun evo = open_res_file("orb_ape.zip");
  const EvoOptions o = options_from_info(evo.info);
  EvalOptions options;
  options.format = o.format;
  options.alignment = o.alignment;
  const EvalResult r = evaluate_files(data_file(o.est_file), data_file(o.gt_file), options);
  const std::string report = format_report(r, options);
  const auto ate = test_support::parse_ate_line(report);
  ASSERT_TRUE(ate.has_value()) << report;
  EXPECT_NEAR(ate->rmse_m, evo.stats.at("rmse").get<double>(), kTolerance);
  EXPECT_NEAR(ate->mean_m, evo.stats.at("mean").get<double>(), kTolerance);
  EXPECT_NEAR(ate->max_m, evo.stats.at("max").get<double>(), kTolerance);
  EXPECT_EQ(ate->poses, read_array(evo.zip, "error_array.npz").size());
  EXPECT_NE(report.find("RPE  RMSE"), std::string::npos) << report;
}

}  // namespace
}  // namespace livod::eval
