// Calibration files: VeloView XML, ROS/nebula YAML, built-in tables, rings, bad files.

#include "drivers/velodyne/calibration.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <fstream>
#include <numbers>

#include "core/error.hpp"
#include "tests/support/data_dir.hpp"

namespace livod::drivers::velodyne {
namespace {

constexpr double kDeg = std::numbers::pi / 180.0;

TEST(Calibration, VeloViewHdl32XmlHas32EnabledLasers) {
  const auto c = load_calibration(livod::test::data_path("velodyne/veloview/HDL-32.xml"));
  ASSERT_EQ(c.lasers.size(), 32U);  // 64 <px> entries, 32 enabled
  EXPECT_NEAR(c.lasers[0].vert_correction_rad, -30.67 * kDeg, 1e-12);
  EXPECT_NEAR(c.lasers[1].vert_correction_rad, -9.3299999 * kDeg, 1e-12);
  EXPECT_NEAR(c.lasers[31].vert_correction_rad, 10.67 * kDeg, 1e-12);
  ASSERT_TRUE(c.distance_resolution_m);
  EXPECT_NEAR(*c.distance_resolution_m, 0.002, 1e-15);  // distLSB_ 0.2 cm
  for (const auto& l : c.lasers) {
    EXPECT_EQ(l.rot_correction_rad, 0.0);
    EXPECT_EQ(l.dist_correction_m, 0.0);
  }
  EXPECT_NO_THROW(check_calibration_matches(c, Model::kHdl32e));
  EXPECT_THROW(check_calibration_matches(c, Model::kVlp16), Error);
}

TEST(Calibration, VeloViewAndNebulaVlp16FilesAgreeWithTheBuiltInTable) {
  const auto xml = load_calibration(livod::test::data_path("velodyne/veloview/VLP-16.xml"));
  const auto yaml = load_calibration(livod::test::data_path("velodyne/nebula_vlp16/VLP16.yaml"));
  const auto builtin = default_calibration(Model::kVlp16);
  ASSERT_EQ(xml.lasers.size(), 16U);
  ASSERT_EQ(yaml.lasers.size(), 16U);
  ASSERT_EQ(builtin.lasers.size(), 16U);
  for (std::size_t i = 0; i < 16; ++i) {
    // Even ids: -15, -13, ..., -1 degrees; odd ids: 1, 3, ..., 15 degrees.
    const double expected =
        (i % 2 == 0 ? -15.0 + static_cast<double>(i) : static_cast<double>(i)) * kDeg;
    EXPECT_NEAR(builtin.lasers[i].vert_correction_rad, expected, 1e-12) << i;
    EXPECT_NEAR(xml.lasers[i].vert_correction_rad, expected, 1e-12) << i;
    EXPECT_NEAR(yaml.lasers[i].vert_correction_rad, expected, 1e-12) << i;
  }
  ASSERT_TRUE(yaml.distance_resolution_m);
  EXPECT_EQ(*yaml.distance_resolution_m, 0.002);
}

TEST(Calibration, RingsSortLasersByElevation) {
  const auto c = default_calibration(Model::kVlp16);
  const auto rings = c.rings();
  // Laser ids 0, 2, ..., 14 point at -15..-1 degrees, 1, 3, ..., 15 at 1..15 degrees.
  for (std::size_t i = 0; i < 16; ++i) {
    EXPECT_EQ(rings[i], i % 2 == 0 ? i / 2 : 8 + i / 2) << i;
  }
  const auto hdl = default_calibration(Model::kHdl32e).rings();
  EXPECT_EQ(hdl[0], 0);    // -30.67
  EXPECT_EQ(hdl[31], 31);  // +10.67
  EXPECT_EQ(hdl[15], 23);  // 0 degrees: 23 beams below it
}

TEST(Calibration, BuiltInTablesFitTheirModels) {
  for (const auto& t : all_models()) {
    const auto c = default_calibration(t.model);
    EXPECT_EQ(static_cast<int>(c.lasers.size()), t.lasers) << t.name;
    EXPECT_NO_THROW(check_calibration_matches(c, t.model)) << t.name;
    // Rings are a permutation.
    auto rings = c.rings();
    std::sort(rings.begin(), rings.end());
    for (std::size_t i = 0; i < rings.size(); ++i) EXPECT_EQ(rings[i], i) << t.name;
  }
  // VLP-32C and VLS-128 beams have rotational corrections (§4.4).
  EXPECT_NEAR(default_calibration(Model::kVlp32c).lasers[1].rot_correction_rad, 4.2 * kDeg, 1e-12);
  EXPECT_NEAR(default_calibration(Model::kVls128).lasers[36].vert_correction_rad, -25 * kDeg,
              1e-12);
}

TEST(Calibration, YamlUnitsAreRadiansAndMetres) {
  const std::string text = R"(
lasers:
  - {laser_id: 1, vert_correction: 0.1, rot_correction: -0.02, dist_correction: 0.05,
     vert_offset_correction: 0.2, horiz_offset_correction: 0.03}
  - {laser_id: 0, vert_correction: -0.1}
num_lasers: 2
distance_resolution: 0.004
)";
  const auto c = parse_ros_yaml(text, "inline");
  ASSERT_EQ(c.lasers.size(), 2U);
  EXPECT_EQ(c.lasers[0].vert_correction_rad, -0.1);
  EXPECT_EQ(c.lasers[1].vert_correction_rad, 0.1);
  EXPECT_EQ(c.lasers[1].rot_correction_rad, -0.02);
  EXPECT_EQ(c.lasers[1].dist_correction_m, 0.05);
  EXPECT_EQ(c.lasers[1].vert_offset_m, 0.2);
  EXPECT_EQ(c.lasers[1].horiz_offset_m, 0.03);
  EXPECT_EQ(*c.distance_resolution_m, 0.004);
}

TEST(Calibration, XmlUnitsAreDegreesAndCentimetres) {
  const std::string text = R"(<?xml version="1.0"?>
<boost_serialization><DB><distLSB_>0.4</distLSB_>
<points_><count>1</count>
<item><px><id_>0</id_><rotCorrection_>-1.5</rotCorrection_><vertCorrection_>2</vertCorrection_>
<distCorrection_>12.5</distCorrection_><vertOffsetCorrection_>20</vertOffsetCorrection_>
<horizOffsetCorrection_>-2.6</horizOffsetCorrection_></px></item>
</points_></DB></boost_serialization>)";
  const auto c = parse_veloview_xml(text, "inline");
  ASSERT_EQ(c.lasers.size(), 1U);
  EXPECT_NEAR(c.lasers[0].rot_correction_rad, -1.5 * kDeg, 1e-15);
  EXPECT_NEAR(c.lasers[0].vert_correction_rad, 2 * kDeg, 1e-15);
  EXPECT_NEAR(c.lasers[0].dist_correction_m, 0.125, 1e-15);
  EXPECT_NEAR(c.lasers[0].vert_offset_m, 0.2, 1e-15);
  EXPECT_NEAR(c.lasers[0].horiz_offset_m, -0.026, 1e-15);
  EXPECT_NEAR(*c.distance_resolution_m, 0.004, 1e-15);
}

TEST(Calibration, MalformedXmlReportsTheByteOffset) {
  const std::string text = "<boost_serialization><DB><points_><item><px><id_>0</id_></px>\n</DB>";
  try {
    (void)parse_veloview_xml(text, "broken.xml");
    FAIL() << "no exception";
  } catch (const FormatError& e) {
    EXPECT_GT(e.offset(), 50U);
    EXPECT_LE(e.offset(), text.size());
    EXPECT_NE(std::string(e.what()).find("broken.xml"), std::string::npos);
  }
  EXPECT_THROW((void)parse_veloview_xml("<a><b>1</b></a>", "empty.xml"), Error);
  const std::string bad_number =
      "<boost_serialization><DB><points_><item><px><id_>0</id_><vertCorrection_>x1"
      "</vertCorrection_></px></item></points_></DB></boost_serialization>";
  EXPECT_THROW((void)parse_veloview_xml(bad_number, "nan.xml"), Error);
}

TEST(Calibration, MalformedYamlIsRejectedClearly) {
  EXPECT_THROW((void)parse_ros_yaml("lasers: [ {laser_id: 0", "broken.yaml"), FormatError);
  EXPECT_THROW((void)parse_ros_yaml("num_lasers: 2\n", "nolasers.yaml"), Error);
  EXPECT_THROW((void)parse_ros_yaml("lasers:\n  - {laser_id: 0}\n  - {laser_id: 0}\n", "dup.yaml"),
               Error);
  EXPECT_THROW((void)parse_ros_yaml("lasers:\n  - {laser_id: 0}\nnum_lasers: 3\n", "count.yaml"),
               Error);
  EXPECT_THROW((void)parse_ros_yaml("lasers:\n  - {laser_id: 0, vert_correction: abc}\n", "t.yaml"),
               FormatError);
}

TEST(Calibration, MissingFileIsAnError) {
  EXPECT_THROW((void)load_calibration("/nonexistent/velodyne.xml"), Error);
}

}  // namespace
}  // namespace livod::drivers::velodyne
