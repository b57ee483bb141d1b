// Trajectory readers on the real files of shared/data/trajectory_eval, and their errors on
// malformed input (line number and byte offset in the message).

#include <gtest/gtest.h>

#include <Eigen/Geometry>
#include <cstdio>
#include <fstream>
#include <sstream>
#include <string>
#include <vector>

#include "core/error.hpp"
#include "tests/support/data_dir.hpp"
#include "tools/eval/trajectory_io.hpp"

namespace livod::eval {
namespace {

std::filesystem::path data_file(const std::string& name) {
  return test::data_path("trajectory_eval/" + name);
}

// The data lines of a file (not blank, not '#'), split on whitespace or commas: an independent
// reading to compare the parsers with.
std::vector<std::vector<std::string>> data_lines(const std::filesystem::path& path, char sep) {
  std::ifstream in(path);
  std::vector<std::vector<std::string>> rows;
  std::string line;
  while (std::getline(in, line)) {
    if (line.empty() || line[0] == '#') continue;
    for (char& c : line) {
      if (c == sep) c = ' ';
    }
    std::istringstream fields(line);
    std::vector<std::string> row;
    std::string f;
    while (fields >> f) row.push_back(f);
    rows.push_back(row);
  }
  return rows;
}

template <class F>
std::string format_error_message(F&& f) {
  try {
    f();
  } catch (const FormatError& e) {
    return e.what();
  }
  ADD_FAILURE() << "no FormatError thrown";
  return {};
}

template <class F>
std::uint64_t format_error_offset(F&& f) {
  try {
    f();
  } catch (const FormatError& e) {
    return e.offset();
  }
  ADD_FAILURE() << "no FormatError thrown";
  return 0;
}

TEST(TrajectoryIo, ReadsKittiPosesAsRowMajorMatrices) {
  const auto path = data_file("KITTI_00_gt.txt");
  const Trajectory t = read_kitti(path);
  const auto rows = data_lines(path, ' ');
  ASSERT_EQ(t.size(), rows.size());
  EXPECT_FALSE(t.has_stamps());
  for (std::size_t i : {std::size_t{0}, std::size_t{1}, rows.size() / 2, rows.size() - 1}) {
    ASSERT_EQ(rows[i].size(), 12u);
    for (int r = 0; r < 3; ++r) {
      for (int c = 0; c < 3; ++c) {
        EXPECT_EQ(t.poses[i].rotation(r, c),
                  std::stod(rows[i][static_cast<std::size_t>(4 * r + c)]));
      }
      EXPECT_EQ(t.poses[i].translation(r), std::stod(rows[i][static_cast<std::size_t>(4 * r + 3)]));
    }
  }
  // KITTI 00 drives several kilometres; positions are metres, not millimetres.
  EXPECT_GT(t.path_length(), 1000.0);
  EXPECT_LT(t.path_length(), 10000.0);
}

TEST(TrajectoryIo, KittiTimesFileStampsThePoses) {
  const Trajectory t = read_kitti(data_file("KITTI_00_gt.txt"), data_file("KITTI_00_gt_times.txt"));
  const auto times = data_lines(data_file("KITTI_00_gt_times.txt"), ' ');
  ASSERT_EQ(t.stamps_s.size(), t.size());
  EXPECT_EQ(t.stamps_s.front(), std::stod(times.front()[0]));
  EXPECT_EQ(t.stamps_s.back(), std::stod(times.back()[0]));
  // A times file of another length is rejected, naming both counts.
  const auto short_times = test::temp_dir("eval_io") / "times.txt";
  std::ofstream(short_times) << "0.0\n0.1\n";
  try {
    read_kitti(data_file("KITTI_00_gt.txt"), short_times);
    ADD_FAILURE() << "no error for a short times file";
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find("has 2 times"), std::string::npos) << e.what();
  }
}

TEST(TrajectoryIo, ReadsTumWithCommentsAndQuaternionOrderXyzw) {
  const auto path = data_file("freiburg1_xyz-groundtruth.txt");
  const Trajectory t = read_tum(path);
  const auto rows = data_lines(path, ' ');
  ASSERT_EQ(t.size(), rows.size());
  ASSERT_TRUE(t.has_stamps());
  for (std::size_t i : {std::size_t{0}, rows.size() / 3, rows.size() - 1}) {
    const auto& r = rows[i];
    EXPECT_EQ(t.stamps_s[i], std::stod(r[0]));
    EXPECT_EQ(t.poses[i].translation,
              Eigen::Vector3d(std::stod(r[1]), std::stod(r[2]), std::stod(r[3])));
    const Eigen::Quaterniond q(std::stod(r[7]), std::stod(r[4]), std::stod(r[5]), std::stod(r[6]));
    EXPECT_LT((t.poses[i].rotation - q.normalized().toRotationMatrix()).norm(), 1e-15);
  }
}

TEST(TrajectoryIo, ReadsEurocCsvWithQuaternionOrderWxyz) {
  const auto path = data_file("V102_groundtruth.csv");
  const Trajectory t = read_euroc_csv(path);
  const auto rows = data_lines(path, ',');
  ASSERT_EQ(t.size(), rows.size());
  for (std::size_t i : {std::size_t{0}, rows.size() - 1}) {
    const auto& r = rows[i];
    EXPECT_DOUBLE_EQ(t.stamps_s[i], static_cast<double>(std::stoll(r[0])) * 1e-9);
    EXPECT_EQ(t.poses[i].translation,
              Eigen::Vector3d(std::stod(r[1]), std::stod(r[2]), std::stod(r[3])));
    const Eigen::Quaterniond q(std::stod(r[4]), std::stod(r[5]), std::stod(r[6]), std::stod(r[7]));
    EXPECT_LT((t.poses[i].rotation - q.normalized().toRotationMatrix()).norm(), 1e-15);
  }
  // Nanoseconds became seconds: the TUM estimate of the same flight starts within it.
  const Trajectory est = read_tum(data_file("V102.txt"));
  EXPECT_GT(est.stamps_s.front(), t.stamps_s.front());
  EXPECT_LT(est.stamps_s.front(), t.stamps_s.back());
}

TEST(TrajectoryIo, ReadsEveryTumFileOfTheDataSet) {
  for (const char* name :
       {"fr2_desk_ORB.txt", "fr2_desk_ORB_kf_mono.txt", "fr2_desk_groundtruth.txt",
        "freiburg1_xyz-ORB_kf_mono.txt", "freiburg1_xyz-rgbdslam.txt",
        "freiburg1_xyz-rgbdslam_drift.txt", "freiburg1_xyz-rgbdslam_drift_short.txt", "V102.txt"}) {
    const auto path = data_file(name);
    const Trajectory t = read_tum(path);
    EXPECT_EQ(t.size(), data_lines(path, ' ').size()) << name;
    for (const RigidTransform3d& p : t.poses) {
      ASSERT_LT((p.rotation.transpose() * p.rotation - Eigen::Matrix3d::Identity()).norm(), 1e-12)
          << name;
    }
  }
}

TEST(TrajectoryIo, AcceptsCrLfTabsBlankLinesAndPlusSigns) {
  const std::string text = "# comment\r\n\r\n1.0\t0 0 0 0 0 0 1\r\n  2.0 +1.5 -2 3e-1 0 0 0 2 \r\n";
  const Trajectory t = parse_tum(text, "mem");
  ASSERT_EQ(t.size(), 2u);
  EXPECT_EQ(t.stamps_s[1], 2.0);
  EXPECT_EQ(t.poses[1].translation, Eigen::Vector3d(1.5, -2, 0.3));
  EXPECT_TRUE(t.poses[1].rotation.isIdentity(0.0));  // (0,0,0,2) normalised to identity
}

TEST(TrajectoryIo, WrongFieldCountNamesTheLineAndItsOffset) {
  const std::string good = "1.0 0 0 0 0 0 0 1\n";
  const std::string text = "# header\n" + good + "2.0 0 0 0 0 0 1\n";
  const std::string msg = format_error_message([&] { parse_tum(text, "est.txt"); });
  EXPECT_NE(msg.find("est.txt"), std::string::npos) << msg;
  EXPECT_NE(msg.find("line 3"), std::string::npos) << msg;
  EXPECT_NE(msg.find("expected 8 values"), std::string::npos) << msg;
  EXPECT_NE(msg.find("found 7"), std::string::npos) << msg;
  EXPECT_EQ(format_error_offset([&] { parse_tum(text, "est.txt"); }),
            std::string("# header\n").size() + good.size());
}

TEST(TrajectoryIo, BadNumberNamesTheFieldOffset) {
  const std::string text = "1.0 0 0 0 0 0 0 1\n2.0 0 x1 0 0 0 0 1\n";
  const std::string msg = format_error_message([&] { parse_tum(text, "f"); });
  EXPECT_NE(msg.find("line 2"), std::string::npos) << msg;
  EXPECT_NE(msg.find("'x1'"), std::string::npos) << msg;
  EXPECT_EQ(format_error_offset([&] { parse_tum(text, "f"); }), text.find("x1"));
  // Not finite, or trailing garbage, is not a number either.
  EXPECT_THROW(parse_tum("1.0 nan 0 0 0 0 0 1\n", "f"), FormatError);
  EXPECT_THROW(parse_tum("1.0 inf 0 0 0 0 0 1\n", "f"), FormatError);
  EXPECT_THROW(parse_tum("1.0 0.5m 0 0 0 0 0 1\n", "f"), FormatError);
}

TEST(TrajectoryIo, RejectsZeroQuaternionsAndTimeGoingBackwards) {
  EXPECT_NE(format_error_message([] { parse_tum("1.0 0 0 0 0 0 0 0\n", "f"); }).find("quaternion"),
            std::string::npos);
  const std::string back = "2.0 0 0 0 0 0 0 1\n1.5 0 0 0 0 0 0 1\n";
  const std::string msg = format_error_message([&] { parse_tum(back, "f"); });
  EXPECT_NE(msg.find("line 2"), std::string::npos) << msg;
  EXPECT_NE(msg.find("earlier"), std::string::npos) << msg;
  // Repeated stamps are allowed.
  EXPECT_EQ(parse_tum("1.0 0 0 0 0 0 0 1\n1.0 0 0 0 0 0 0 1\n", "f").size(), 2u);
}

TEST(TrajectoryIo, KittiAndTimesAndCsvErrors) {
  const std::string kitti_bad = "1 0 0 0 0 1 0 0 0 0 1 0\n1 0 0 0 0 1 0 0 0 0 1\n";
  const std::string msg = format_error_message([&] { parse_kitti(kitti_bad, "k"); });
  EXPECT_NE(msg.find("line 2"), std::string::npos) << msg;
  EXPECT_NE(msg.find("expected 12 values"), std::string::npos) << msg;
  EXPECT_THROW(parse_times("0.0\n0.1 0.2\n", "t"), FormatError);
  EXPECT_THROW(parse_times("0.2\n0.1\n", "t"), FormatError);
  // EuRoC stamps are integer nanoseconds.
  const std::string csv = "#timestamp,x,y,z,qw,qx,qy,qz\n1.5,0,0,0,1,0,0,0\n";
  const std::string csv_msg = format_error_message([&] { parse_euroc_csv(csv, "c"); });
  EXPECT_NE(csv_msg.find("not an integer"), std::string::npos) << csv_msg;
  EXPECT_THROW(parse_euroc_csv("100,0,0,0,1,0,0\n", "c"), FormatError);
  EXPECT_THROW(parse_euroc_csv("100,0,0,,1,0,0,0\n", "c"), FormatError);
  const Trajectory ok = parse_euroc_csv("100, 1, 2, 3, 1, 0, 0, 0, 9, 9\n", "c");
  ASSERT_EQ(ok.size(), 1u);
  EXPECT_EQ(ok.poses[0].translation, Eigen::Vector3d(1, 2, 3));
}

TEST(TrajectoryIo, MissingFileIsAnError) {
  EXPECT_THROW(read_tum("/nonexistent/trajectory.txt"), Error);
}

TEST(TrajectoryIo, FormatNamesRoundTrip) {
  for (TrajectoryFormat f :
       {TrajectoryFormat::kTum, TrajectoryFormat::kKitti, TrajectoryFormat::kEuroc}) {
    EXPECT_EQ(parse_trajectory_format(to_string(f)), f);
  }
  EXPECT_FALSE(parse_trajectory_format("bag").has_value());
}

}  // namespace
}  // namespace livod::eval
