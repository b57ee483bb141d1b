// Model name -> decoder table.

#include "drivers/registry.hpp"

#include <gtest/gtest.h>

#include "core/error.hpp"
#include "tests/support/data_dir.hpp"

namespace livod::drivers {
namespace {

TEST(Registry, VelodyneModelsAreRegisteredAndMatchedLoosely) {
  for (const char* name :
       {"VLP-16", "vlp16", "Vlp_16", "VLP-32C", "HDL-32E", "hdl32e", "VLS-128", "PUCK-HI-RES"}) {
    const DecoderEntry* entry = find_decoder(name);
    ASSERT_NE(entry, nullptr) << name;
    EXPECT_EQ(entry->family, "velodyne");
    DecoderConfig config;
    config.model = name;
    const auto decoder = make_decoder(config);
    ASSERT_NE(decoder, nullptr);
    EXPECT_EQ(decoder->model_name(), entry->model);
    EXPECT_EQ(decoder->default_ports(), (std::vector<std::uint16_t>{2368, 8308}));
  }
  const std::string list = known_models();
  EXPECT_NE(list.find("VLP-16"), std::string::npos);
  EXPECT_NE(list.find("VLS-128"), std::string::npos);
}

TEST(Registry, UnknownModelsListTheKnownOnes) {
  EXPECT_EQ(find_decoder("VLP-64"), nullptr);
  DecoderConfig config;
  config.model = "VLP-64";
  try {
    (void)make_decoder(config);
    FAIL() << "no exception";
  } catch (const Error& e) {
    const std::string what = e.what();
    EXPECT_NE(what.find("VLP-64"), std::string::npos);
    EXPECT_NE(what.find(known_models()), std::string::npos);
  }
}

TEST(Registry, VelodyneFactoriesUseTheCalibrationAndRejectMetadata) {
  DecoderConfig config;
  config.model = "HDL-32E";
  config.calibration = livod::test::data_path("velodyne/veloview/HDL-32.xml");
  EXPECT_NE(make_decoder(config), nullptr);
  config.model = "VLP-16";  // a 32-laser file for a 16-laser sensor
  EXPECT_THROW((void)make_decoder(config), Error);
  config.calibration.reset();
  config.metadata = livod::test::data_path("velodyne/veloview/HDL-32.xml");
  EXPECT_THROW((void)make_decoder(config), Error);
}

}  // namespace
}  // namespace livod::drivers
