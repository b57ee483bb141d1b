// Time association against a direct transcription of evo's rule (for every stamp of the
// shorter trajectory, argmin over all stamps of the longer one), on the real TUM files.

#include <gtest/gtest.h>

#include <cmath>
#include <string>
#include <vector>

#include "core/error.hpp"
#include "tests/support/data_dir.hpp"
#include "tools/eval/association.hpp"
#include "tools/eval/trajectory_io.hpp"

namespace livod::eval {
namespace {

Trajectory tum(const std::string& name) {
  return read_tum(test::data_path("trajectory_eval/" + name));
}

// O(n·m) reference: the first index of the smallest |t_long + shift − t_short|.
Association brute_force(const Trajectory& gt, const Trajectory& est, double max_diff,
                        double offset) {
  Association a;
  const bool est_longer = est.size() > gt.size();
  const Trajectory& s = est_longer ? gt : est;
  const Trajectory& l = est_longer ? est : gt;
  const double shift = est_longer ? offset : -offset;
  for (std::size_t i = 0; i < s.size(); ++i) {
    std::size_t best = 0;
    double best_diff = INFINITY;
    for (std::size_t j = 0; j < l.size(); ++j) {
      const double d = std::abs(l.stamps_s[j] + shift - s.stamps_s[i]);
      if (d < best_diff) {
        best_diff = d;
        best = j;
      }
    }
    if (best_diff <= max_diff) {
      (est_longer ? a.gt_index : a.est_index).push_back(i);
      (est_longer ? a.est_index : a.gt_index).push_back(best);
    }
  }
  return a;
}

void expect_same(const Association& a, const Association& b) {
  EXPECT_EQ(a.gt_index, b.gt_index);
  EXPECT_EQ(a.est_index, b.est_index);
}

TEST(Association, MatchesTheExhaustiveRuleOnRealFiles) {
  const Trajectory gt1 = tum("freiburg1_xyz-groundtruth.txt");
  const Trajectory gt2 = tum("fr2_desk_groundtruth.txt");
  struct Case {
    const Trajectory* gt;
    std::string est;
    double max_diff;
    double offset;
  };
  const std::vector<Case> cases = {
      {&gt1, "freiburg1_xyz-rgbdslam.txt", 0.01, 0.0},
      {&gt1, "freiburg1_xyz-ORB_kf_mono.txt", 0.01, 0.0},
      {&gt1, "freiburg1_xyz-rgbdslam.txt", 0.02, 0.013},
      {&gt2, "fr2_desk_ORB.txt", 0.01, 0.0},
      {&gt2, "fr2_desk_ORB_kf_mono.txt", 0.005, -0.2},
  };
  for (const Case& c : cases) {
    SCOPED_TRACE(c.est);
    const Trajectory est = tum(c.est);
    const Association fast = associate_by_time(*c.gt, est, c.max_diff, c.offset);
    expect_same(fast, brute_force(*c.gt, est, c.max_diff, c.offset));
    EXPECT_GT(fast.size(), 0u);
    for (std::size_t k = 0; k < fast.size(); ++k) {
      ASSERT_LE(
          std::abs(est.stamps_s[fast.est_index[k]] + c.offset - c.gt->stamps_s[fast.gt_index[k]]),
          c.max_diff);
    }
  }
}

TEST(Association, IteratesTheShorterTrajectory) {
  // A ground truth shorter than the estimate: every ground-truth stamp looks for an estimate.
  const Trajectory gt = tum("freiburg1_xyz-rgbdslam_drift_short.txt");
  const Trajectory est = tum("freiburg1_xyz-groundtruth.txt");
  ASSERT_LT(gt.size(), est.size());
  const Association a = associate_by_time(gt, est, 0.01, 0.0);
  expect_same(a, brute_force(gt, est, 0.01, 0.0));
  for (std::size_t k = 1; k < a.size(); ++k) EXPECT_LT(a.gt_index[k - 1], a.gt_index[k]);
}

TEST(Association, OffsetCompensatesAShiftedClock) {
  const Trajectory gt = tum("freiburg1_xyz-groundtruth.txt");
  const Trajectory est = tum("freiburg1_xyz-rgbdslam.txt");
  Trajectory shifted = est;
  for (double& t : shifted.stamps_s) t -= 3.25;  // estimate clock runs 3.25 s behind
  const Association reference = associate_by_time(gt, est, 0.01, 0.0);
  expect_same(associate_by_time(gt, shifted, 0.01, 3.25), reference);
  // Without the offset, the estimate's poses pair with ground truth 3.25 s away from their own.
  const Association wrong = associate_by_time(gt, shifted, 0.01, 0.0);
  EXPECT_NE(wrong.gt_index, reference.gt_index);
}

TEST(Association, TiesGoToTheEarlierStamp) {
  Trajectory gt;
  gt.stamps_s = {1.0, 2.0, 2.0, 3.0};
  gt.poses.resize(4);
  Trajectory est;
  est.stamps_s = {1.5, 2.0};
  est.poses.resize(2);
  const Association a = associate_by_time(gt, est, 0.5, 0.0);
  EXPECT_EQ(a.est_index, (std::vector<std::size_t>{0, 1}));
  EXPECT_EQ(a.gt_index, (std::vector<std::size_t>{0, 1}));
  expect_same(a, brute_force(gt, est, 0.5, 0.0));
}

TEST(Association, ByIndexNeedsEqualLengths) {
  Trajectory a;
  a.poses.resize(3);
  Trajectory b;
  b.poses.resize(4);
  EXPECT_THROW(associate_by_index(a, b), Error);
  b.poses.resize(3);
  const Association ab = associate_by_index(a, b);
  EXPECT_EQ(ab.gt_index, (std::vector<std::size_t>{0, 1, 2}));
  EXPECT_EQ(ab.est_index, ab.gt_index);
  EXPECT_THROW(associate_by_time(a, b, 0.01, 0.0), Error);  // no stamps
}

}  // namespace
}  // namespace livod::eval
