// The families' descriptor tables: one place per family for model names and aliases, ports,
// internal IMUs, cuts, files and factories.

#include "drivers/lidar_family.hpp"

#include <gtest/gtest.h>

#include <set>

#include "core/error.hpp"
#include "drivers/hesai/settings.hpp"
#include "tests/support/data_dir.hpp"

namespace livod::drivers {
namespace {

TEST(LidarFamilies, EveryFamilyIsCompleteAndNamesAreUnique) {
  std::set<std::string> drivers_seen;
  std::set<std::string> models_seen;
  for (const LidarFamily* f : lidar_families()) {
    SCOPED_TRACE(std::string(f->driver));
    EXPECT_TRUE(drivers_seen.insert(std::string(f->driver)).second);
    EXPECT_EQ(find_family(f->driver), f);
    ASSERT_FALSE(f->models.empty());
    ASSERT_FALSE(f->cut_modes.empty());
    ASSERT_FALSE(f->port_names.empty());
    EXPECT_EQ(f->port_names.front(), "lidar");
    EXPECT_NE(f->make_decoder, nullptr);
    for (const LidarModelInfo& m : f->models) {
      // A name or alias names one model of one family, whatever its spelling.
      EXPECT_TRUE(models_seen.insert(normalise_model_name(m.name)).second) << m.name;
      for (const auto alias : m.aliases) {
        EXPECT_TRUE(models_seen.insert(normalise_model_name(alias)).second) << alias;
        EXPECT_EQ(f->find_model(alias), &m);
      }
      const auto match = find_model(m.name);
      ASSERT_TRUE(match);
      EXPECT_EQ(match->family, f);
      EXPECT_EQ(match->model, &m);
      EXPECT_NE(m.ports.lidar, 0) << m.name;
      EXPECT_GE(m.beams, 0);
      EXPECT_FALSE(m.summary.empty());
    }
  }
  EXPECT_EQ(find_family("v4l2"), nullptr);
}

TEST(LidarFamilies, ModelNamesMatchLoosely) {
  for (const char* name : {"VLP-16", "vlp16", "Vlp_16", "puck", "PUCK-HI-RES", "hdl32e", "os-1-64",
                           "OS1_128", "mid360", "Tele 15", "PandarXT32", "xt32", "pandar40p"}) {
    EXPECT_TRUE(find_model(name)) << name;
  }
  EXPECT_EQ(find_model("os-1-64")->model->name, "OS1-64");
  EXPECT_EQ(find_model("xt32")->family->driver, "hesai");
  EXPECT_EQ(find_model("Puck")->model->name, "VLP-16");
  EXPECT_FALSE(find_model("VLP-64"));
  EXPECT_NE(all_model_names().find("PANDAR40P"), std::string::npos);
}

TEST(LidarFamilies, FactsTheRestOfLivodAsks) {
  EXPECT_TRUE(find_model("HDL-32E")->model->internal_imu);
  EXPECT_FALSE(find_model("VLP-16")->model->internal_imu);
  EXPECT_FALSE(find_model("MID-40")->model->internal_imu);
  EXPECT_TRUE(find_model("MID-360")->model->internal_imu);
  EXPECT_FALSE(find_model("PANDARXT32")->model->internal_imu);
  EXPECT_EQ(find_model("MID-360")->model->ports.imu, 56401);
  EXPECT_EQ(find_model("HAP")->model->ports.lidar, 57000);
  EXPECT_EQ(find_model("PANDAR40P")->model->ports.position, 10110);
  EXPECT_EQ(find_model("OS2-128")->model->beams, 128);
  EXPECT_DOUBLE_EQ(find_model("PANDARXT32")->model->points_per_second, 640'000.0);
  EXPECT_TRUE(find_family("velodyne")->allows(CutMode::kAzimuth));
  EXPECT_FALSE(find_family("ouster")->allows(CutMode::kTime));  // frames are the sensor's own
  EXPECT_EQ(find_family("livox_sdk2")->default_cut(), CutMode::kTime);
  EXPECT_EQ(find_family("velodyne")->sensor_time_wrap_ns, 3'600'000'000'000LL);
  EXPECT_EQ(find_family("hesai")->file, DecoderFile::kCalibrationRequired);
}

TEST(LidarFamilies, FactoriesBuildTheirDecodersAndRefuseWhatDoesNotApply) {
  LidarDecoderConfig config;
  config.model = "vlp16";
  auto velodyne = make_lidar_decoder(config);
  EXPECT_EQ(velodyne->model_name(), "VLP-16");
  EXPECT_EQ(velodyne->default_ports(), (std::vector<std::uint16_t>{2368, 8308}));
  config.metadata = test::data_path("velodyne/veloview/HDL-32.xml");
  EXPECT_THROW((void)make_lidar_decoder(config), Error);  // metadata is Ouster's

  LidarDecoderConfig hesai;
  hesai.model = "PANDARXT32";
  EXPECT_THROW((void)make_lidar_decoder(hesai), Error);  // its angle file is required
  hesai.calibration = test::data_path("hesai/PandarXT32.csv");
  hesai.settings = hesai::HesaiSettings{};
  EXPECT_EQ(make_lidar_decoder(hesai)->default_ports(), (std::vector<std::uint16_t>{2368, 10110}));
  hesai.cut = FrameCut{CutMode::kFrameId, 0.0, 0.1};
  EXPECT_THROW((void)make_lidar_decoder(hesai), Error);

  LidarDecoderConfig livox;
  livox.model = "MID-360";
  livox.cut = FrameCut{CutMode::kAzimuth, 0.0, 0.1};
  EXPECT_THROW((void)make_lidar_decoder(livox), Error);  // time windows only
  livox.cut = FrameCut{CutMode::kTime, 0.0, 0.05};
  EXPECT_EQ(make_lidar_decoder(livox)->model_name(), "MID-360");

  LidarDecoderConfig unknown;
  unknown.model = "VLP-64";
  try {
    (void)make_lidar_decoder(unknown);
    FAIL() << "no exception";
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find(all_model_names()), std::string::npos);
  }
}

}  // namespace
}  // namespace livod::drivers
