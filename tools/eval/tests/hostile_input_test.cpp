// `livod eval` on inputs that used to give quietly wrong numbers (issue 14): repeated stamps,
// absurd coordinates, an alignment from two poses, a device instead of a file.

#include <gtest/gtest.h>

#include <cmath>
#include <fstream>
#include <string>

#include "core/error.hpp"
#include "tests/support/data_dir.hpp"
#include "tools/eval/evaluate.hpp"
#include "tools/eval/trajectory_io.hpp"

namespace livod::eval {
namespace {

// A curved walk at 10 Hz, as TUM text; every pose written `copies` times.
std::string walk(int poses, int copies, double scale = 1.0) {
  std::string text;
  for (int i = 0; i < poses; ++i) {
    const double t = 0.1 * i;
    for (int c = 0; c < copies; ++c) {
      text += std::to_string(100.0 + t) + " " + std::to_string(scale * std::cos(t)) + " " +
              std::to_string(scale * std::sin(t)) + " " + std::to_string(0.1 * t) + " 0 0 0 1\n";
    }
  }
  return text;
}

std::filesystem::path write(const std::string& name, const std::string& text) {
  const auto path = test::temp_dir("eval_hostile_" + name) / name;
  std::ofstream(path) << text;
  return path;
}

TEST(EvalHostileInput, RepeatedStampsAreDroppedWithAWarningAndDoNotChangeRpe) {
  // The estimate drifts a little from the ground truth, so that RPE is not zero.
  std::string est_text;
  for (int i = 0; i < 50; ++i) {
    const double t = 0.1 * i;
    est_text += std::to_string(100.0 + t) + " " + std::to_string(std::cos(t) + 0.01 * i) + " " +
                std::to_string(std::sin(t)) + " " + std::to_string(0.1 * t) + " 0 0 0 1\n";
  }
  std::string doubled;
  for (std::size_t start = 0; start < est_text.size();) {
    const std::size_t end = est_text.find('\n', start) + 1;
    doubled += est_text.substr(start, end - start) + est_text.substr(start, end - start);
    start = end;
  }
  const auto gt = write("gt.txt", walk(50, 1));
  const EvalOptions options;
  const EvalResult once = evaluate_files(write("once.txt", est_text), gt, options);
  const EvalResult twice = evaluate_files(write("twice.txt", doubled), gt, options);
  ASSERT_TRUE(once.rpe_translation && twice.rpe_translation);
  EXPECT_GT(once.rpe_translation->rmse, 0.0);
  EXPECT_DOUBLE_EQ(twice.rpe_translation->rmse, once.rpe_translation->rmse);
  EXPECT_DOUBLE_EQ(twice.ape.rmse, once.ape.rmse);
  EXPECT_TRUE(once.warnings.empty());
  ASSERT_EQ(twice.warnings.size(), 1u);
  EXPECT_NE(twice.warnings[0].find("estimate repeats the timestamp of the previous pose 50"),
            std::string::npos)
      << twice.warnings[0];
  EXPECT_NE(format_report(twice, options).find("warning"), std::string::npos);
}

TEST(EvalHostileInput, AbsurdCoordinatesAreRejectedWithTheLine) {
  std::string text = walk(10, 1);
  text += "101.5 1e300 0 0 0 0 0 1\n";
  const auto path = write("huge.txt", text);
  try {
    (void)read_tum(path);
    FAIL() << "read 1e300 m";
  } catch (const FormatError& e) {
    EXPECT_NE(std::string(e.what()).find("line 11"), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("beyond 1e7 m"), std::string::npos) << e.what();
  }
}

TEST(EvalHostileInput, AlignmentNeedsThreePairsAndWarnsBelowTen) {
  const auto two = write("two.txt", walk(2, 1));
  EvalOptions options;
  try {
    (void)evaluate_files(two, two, options);
    FAIL() << "aligned from two poses";
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find("at least 3"), std::string::npos) << e.what();
  }
  options.alignment = Alignment::kNone;
  EXPECT_NO_THROW((void)evaluate_files(two, two, options));
  options.alignment = Alignment::kSe3;
  const auto five = write("five.txt", walk(5, 1));
  const EvalResult r = evaluate_files(five, five, options);
  ASSERT_EQ(r.warnings.size(), 1u);
  EXPECT_NE(r.warnings[0].find("only 5 pose pairs"), std::string::npos) << r.warnings[0];
}

TEST(EvalHostileInput, DevicesAndBinaryFilesAreRefusedAfterOneBlock) {
  try {
    (void)read_tum("/dev/zero");
    FAIL() << "read /dev/zero";
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find("not a text file"), std::string::npos) << e.what();
  }
}

}  // namespace
}  // namespace livod::eval
