// Which scans go into the map (map/insert_gate.hpp): the first sweep always, then only from a new
// viewpoint - moved or turned far enough since the last inserted sweep, measured from that one
// (not from the previous scan, so a slow creep is inserted once it adds up) - and a sweep whole or
// not at all when a camera cuts it into several groups.

#include "estimator/map/insert_gate.hpp"

#include <gtest/gtest.h>

#include <Eigen/Geometry>
#include <chrono>

#include "core/units.hpp"

namespace livod::estimator {
namespace {

using std::chrono::milliseconds;

constexpr double kDeg = kDegToRad;
constexpr Nanoseconds kPeriod = milliseconds(100);  // a 10 Hz LiDAR

Eigen::Matrix3d yaw(double rad) {
  return Eigen::AngleAxisd(rad, Eigen::Vector3d::UnitZ()).matrix();
}

MappedTime at_ms(int ms) {
  return MappedTime{} + milliseconds(ms);
}

// Whole-scan groups: scan k is measured in (100 k, 100 (k + 1)] ms.
bool admit_scan(MapInsertGate& gate, int k, const Eigen::Matrix3d& R, const Eigen::Vector3d& p) {
  return gate.admit(at_ms(100 * k), at_ms(100 * (k + 1)), kPeriod, R, p);
}

TEST(MapInsertGate, OffInsertsEveryScan) {
  MapInsertGate gate(0.0, 10.0 * kDeg);
  for (int k = 0; k < 5; ++k) {
    EXPECT_TRUE(admit_scan(gate, k, Eigen::Matrix3d::Identity(), Eigen::Vector3d::Zero()));
  }
}

TEST(MapInsertGate, StandingStillInsertsTheFirstScanOnly) {
  MapInsertGate gate(0.5, 10.0 * kDeg);
  const Eigen::Vector3d here(1, 2, 3);
  EXPECT_TRUE(admit_scan(gate, 0, Eigen::Matrix3d::Identity(), here));
  for (int k = 1; k < 20; ++k) {
    // The estimate jitters by a millimetre and a tenth of a degree.
    EXPECT_FALSE(admit_scan(gate, k, yaw(0.1 * kDeg * (k % 2)),
                            here + Eigen::Vector3d(0, 0, 0.001 * (k % 2))))
        << k;
  }
}

TEST(MapInsertGate, CreepingAddsUpFromTheLastInsertedScan) {
  MapInsertGate gate(0.5, 10.0 * kDeg);
  const Eigen::Matrix3d I = Eigen::Matrix3d::Identity();
  EXPECT_TRUE(admit_scan(gate, 0, I, Eigen::Vector3d::Zero()));
  // 0.1 m a scan: scans 1-4 are within 0.5 m of the inserted one, scan 5 reaches it.
  for (int k = 1; k <= 4; ++k) {
    EXPECT_FALSE(admit_scan(gate, k, I, Eigen::Vector3d(0.1 * k, 0, 0))) << k;
  }
  EXPECT_TRUE(admit_scan(gate, 5, I, Eigen::Vector3d(0.5, 0, 0)));
  // Measured from the newly inserted pose now.
  EXPECT_FALSE(admit_scan(gate, 6, I, Eigen::Vector3d(0.9, 0, 0)));
  EXPECT_TRUE(admit_scan(gate, 7, I, Eigen::Vector3d(0.5, -0.5, 0)));
  // Driving (1 m a scan): every scan.
  for (int k = 8; k < 12; ++k) {
    EXPECT_TRUE(admit_scan(gate, k, I, Eigen::Vector3d(k - 7.0, -0.5, 0))) << k;
  }
}

TEST(MapInsertGate, TurningInPlaceIsANewViewpoint) {
  MapInsertGate gate(0.5, 10.0 * kDeg);
  const Eigen::Vector3d here(4, 0, 1);
  EXPECT_TRUE(admit_scan(gate, 0, yaw(0.0), here));
  EXPECT_FALSE(admit_scan(gate, 1, yaw(9.0 * kDeg), here));
  EXPECT_FALSE(admit_scan(gate, 2, yaw(-1.0 * kDeg), here));
  EXPECT_TRUE(admit_scan(gate, 3, yaw(10.5 * kDeg), here));
  // Back to the first heading: 10.5 degrees from the last inserted one.
  EXPECT_TRUE(admit_scan(gate, 4, yaw(0.0), here));
}

// A 20 Hz camera beside the 10 Hz LiDAR: groups of half a scan. The second half of an admitted
// sweep goes in with it (even if the sensor has not moved since), the next sweep is decided anew.
TEST(MapInsertGate, ASweepCutByImagesGoesInWhole) {
  MapInsertGate gate(0.5, 10.0 * kDeg);
  const Eigen::Matrix3d I = Eigen::Matrix3d::Identity();
  const Eigen::Vector3d here = Eigen::Vector3d::Zero();
  const auto half = [&](int h, const Eigen::Vector3d& p) {
    return gate.admit(at_ms(50 * h), at_ms(50 * (h + 1)), kPeriod, I, p);
  };
  EXPECT_TRUE(half(0, here));
  EXPECT_TRUE(half(1, here));   // the same sweep
  EXPECT_FALSE(half(2, here));  // a new sweep from the same place
  EXPECT_FALSE(half(3, here));
  // Moved: the sweep is admitted at the group where that is decided, the next half with it.
  EXPECT_TRUE(half(4, Eigen::Vector3d(0.6, 0, 0)));
  EXPECT_TRUE(half(5, Eigen::Vector3d(0.6, 0, 0)));
  EXPECT_FALSE(half(6, Eigen::Vector3d(0.6, 0, 0)));
  // Image times jitter: the sweep's last group may end a little after a period (up to a tenth).
  EXPECT_TRUE(gate.admit(at_ms(350), at_ms(404), kPeriod, I, Eigen::Vector3d(1.2, 0, 0)));
  EXPECT_TRUE(gate.admit(at_ms(404), at_ms(458), kPeriod, I, Eigen::Vector3d(1.2, 0, 0)));
  EXPECT_FALSE(gate.admit(at_ms(458), at_ms(500), kPeriod, I, Eigen::Vector3d(1.2, 0, 0)));
}

}  // namespace
}  // namespace livod::estimator
