// `livod eval` end to end through the library: read real files, associate, align, report, plot.
// The PNG must exist and decode; trajectories and the error curve must be drawn in it.

#include <gtest/gtest.h>

#include <opencv2/core.hpp>
#include <opencv2/imgcodecs.hpp>
#include <string>

#include "core/error.hpp"
#include "tests/support/data_dir.hpp"
#include "tools/eval/evaluate.hpp"
#include "tools/eval/plot.hpp"
#include "tools/eval/tests/report_line.hpp"

namespace livod::eval {
namespace {

std::filesystem::path data_file(const std::string& name) {
  return test::data_path("trajectory_eval/" + name);
}

// Pixels that are neither white (background) nor grey (grid/frame): data drawn in colour.
int coloured_pixels(const cv::Mat& img, const cv::Rect& area) {
  int n = 0;
  const cv::Mat roi = img(area);
  for (int y = 0; y < roi.rows; ++y) {
    for (int x = 0; x < roi.cols; ++x) {
      const cv::Vec3b p = roi.at<cv::Vec3b>(y, x);
      const int spread = std::max({p[0], p[1], p[2]}) - std::min({p[0], p[1], p[2]});
      if (spread > 60) ++n;
    }
  }
  return n;
}

TEST(EndToEnd, TumFilesGiveAReportAndADecodablePlot) {
  EvalOptions options;
  options.format = TrajectoryFormat::kTum;
  options.alignment = Alignment::kSe3;
  options.rpe_delta = 1.0;
  options.rpe_unit = DeltaUnit::kSeconds;
  const EvalResult r = evaluate_files(data_file("freiburg1_xyz-rgbdslam.txt"),
                                      data_file("freiburg1_xyz-groundtruth.txt"), options);
  EXPECT_TRUE(r.associated_by_time);
  EXPECT_GT(r.gt.size(), r.est_poses_read / 2);
  ASSERT_TRUE(r.rpe_translation.has_value());

  const std::string report = format_report(r, options);
  const auto ate = test_support::parse_ate_line(report);
  ASSERT_TRUE(ate.has_value()) << report;
  EXPECT_NEAR(ate->rmse_m, r.ape.rmse, 1e-6);
  EXPECT_EQ(ate->poses, r.gt.size());
  EXPECT_NE(report.find("RPE  RMSE"), std::string::npos) << report;
  EXPECT_NE(report.find("delta 1 s"), std::string::npos) << report;

  const auto png = test::temp_dir("eval_e2e") / "fr1_xyz.png";
  write_plot(png, r, "freiburg1_xyz rgbdslam");
  ASSERT_TRUE(std::filesystem::exists(png));
  const cv::Mat img = cv::imread(png.string(), cv::IMREAD_COLOR);
  ASSERT_FALSE(img.empty()) << "PNG does not decode";
  EXPECT_EQ(img.type(), CV_8UC3);
  EXPECT_GT(img.cols, img.rows);
  // Both halves hold coloured data: the estimate's path on the left, the error curve on the right.
  EXPECT_GT(coloured_pixels(img, cv::Rect(0, 0, img.cols / 2, img.rows)), 200);
  EXPECT_GT(coloured_pixels(img, cv::Rect(img.cols / 2, 0, img.cols / 2, img.rows)), 200);
}

TEST(EndToEnd, EurocCsvGroundTruthWithTumEstimate) {
  EvalOptions options;
  options.format = TrajectoryFormat::kEuroc;
  const EvalResult r =
      evaluate_files(data_file("V102.txt"), data_file("V102_groundtruth.csv"), options);
  // Ground truth at 200 Hz pairs nearly every estimate stamp within 10 ms (the estimate runs
  // a little past the end of the ground truth).
  EXPECT_GT(r.gt.size(), r.est_poses_read * 95 / 100);
  EXPECT_LE(r.gt.size(), r.est_poses_read);
  // A VIO estimate of a room-sized flight: centimetres to decimetres, not metres.
  EXPECT_LT(r.ape.rmse, 0.5);
  EXPECT_GT(r.ape.rmse, 0.0);
}

TEST(EndToEnd, Sim3AlignmentFixesMonocularScale) {
  EvalOptions options;
  options.alignment = Alignment::kSe3;
  const auto est = data_file("fr2_desk_ORB_kf_mono.txt");
  const auto gt = data_file("fr2_desk_groundtruth.txt");
  const EvalResult rigid = evaluate_files(est, gt, options);
  options.alignment = Alignment::kSim3;
  const EvalResult similar = evaluate_files(est, gt, options);
  EXPECT_EQ(rigid.alignment.scale, 1.0);
  EXPECT_NE(similar.alignment.scale, 1.0);
  EXPECT_LT(similar.ape.rmse, rigid.ape.rmse);
}

TEST(EndToEnd, KittiWithTimesFilePlotsOverSeconds) {
  EvalOptions options;
  options.format = TrajectoryFormat::kKitti;
  options.kitti_times = data_file("KITTI_00_gt_times.txt");
  options.rpe_delta = 10.0;
  options.rpe_unit = DeltaUnit::kSeconds;
  const EvalResult r =
      evaluate_files(data_file("KITTI_00_ORB.txt"), data_file("KITTI_00_gt.txt"), options);
  EXPECT_FALSE(r.associated_by_time);
  ASSERT_TRUE(r.gt.has_stamps());
  ASSERT_TRUE(r.rpe_translation.has_value());
  for (const auto& [i, j] : r.rpe.pairs) {
    ASSERT_GE(r.gt.stamps_s[j] - r.gt.stamps_s[i], 10.0);
  }
  const auto png = test::temp_dir("eval_kitti") / "kitti.png";
  write_plot(png, r, "KITTI 00 ORB");
  EXPECT_FALSE(cv::imread(png.string()).empty());
}

TEST(EndToEnd, UnwritablePlotPathIsAnError) {
  EvalOptions options;
  const EvalResult r = evaluate_files(data_file("freiburg1_xyz-rgbdslam_drift_short.txt"),
                                      data_file("freiburg1_xyz-groundtruth.txt"), options);
  EXPECT_THROW(write_plot("/nonexistent-dir/x.png", r, "x"), Error);
}

TEST(EndToEnd, ShortTrajectoryReportsNoRpePair) {
  EvalOptions options;
  options.rpe_delta = 1000.0;
  options.rpe_unit = DeltaUnit::kMeters;
  const EvalResult r = evaluate_files(data_file("freiburg1_xyz-rgbdslam_drift_short.txt"),
                                      data_file("freiburg1_xyz-groundtruth.txt"), options);
  EXPECT_FALSE(r.rpe_translation.has_value());
  EXPECT_NE(format_report(r, options).find("RPE  no pose pair"), std::string::npos);
}

}  // namespace
}  // namespace livod::eval
