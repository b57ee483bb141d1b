#include "tools/sim/lidar_registry.hpp"

#include <algorithm>
#include <functional>

#include "core/error.hpp"
#include "drivers/lidar_family.hpp"
#include "tools/sim/hesai_sim.hpp"
#include "tools/sim/livox_sim.hpp"
#include "tools/sim/ouster_sim.hpp"
#include "tools/sim/velodyne_sim.hpp"

namespace livod::sim {
namespace {

// What the model is (name, internal IMU, family) comes from the LiDAR families' tables
// (drivers/lidar_family.hpp); this table only says which models the simulator writes.
struct Entry {
  const char* model;
  const char* description;
  std::function<std::unique_ptr<SimLidar>(const SimLidarOptions&)> make;
};

// One line per simulated model (SIM-LIDAR-REGISTRY).
std::vector<Entry> entries() {
  return {
      {"AVIA", "Livox Avia (SDK1), 6-line rosette, 240 kpts/s, internal IMU", make_sim_avia},
      {"MID-360", "Livox Mid-360 (SDK2), 360 deg, 4 lines, 200 kpts/s, internal IMU",
       make_sim_mid360},
      {"OS1-64", "Ouster OS1-64, 1024x10, RNG19_RFL8_SIG16_NIR16, FW 2.5, internal IMU",
       make_sim_os1_64},
      {"OS1-128", "Ouster OS1-128, 1024x10, RNG19_RFL8_SIG16_NIR16, FW 2.5, internal IMU",
       make_sim_os1_128},
      {"VLP-16", "Velodyne VLP-16, 600 RPM, data + position packets", make_sim_vlp16},
      {"HDL-32E",
       "Velodyne HDL-32E, 600 RPM, data + position packets, internal IMU in the position packets",
       make_sim_hdl32e},
      {"PANDARXT32",
       "Hesai PandarXT-32, 600 RPM, single return, UDP sequence, angle correction file beside "
       "the capture",
       make_sim_pandar_xt32},
      // SIM-LIDAR-REGISTRY: one line per simulated model
  };
}

}  // namespace

std::vector<std::pair<std::string, std::string>> simulated_lidar_models() {
  std::vector<std::pair<std::string, std::string>> out;
  for (const auto& e : entries()) out.emplace_back(e.model, e.description);
  return out;
}

bool simulated_lidar_has_imu(const std::string& model) {
  const auto all = entries();
  const bool simulated =
      std::any_of(all.begin(), all.end(), [&](const Entry& e) { return model == e.model; });
  const auto match = drivers::find_model(model);
  return simulated && match && match->model->internal_imu;
}

std::unique_ptr<SimLidar> make_sim_lidar(const std::string& model, const SimLidarOptions& options) {
  for (const auto& e : entries()) {
    if (model == e.model) return e.make(options);
  }
  std::string known;
  for (const auto& e : entries()) known += std::string(known.empty() ? "" : ", ") + e.model;
  throw Error("the simulator has no LiDAR model '" + model +
              "' (simulated models: " + (known.empty() ? "none yet" : known) + ")");
}

}  // namespace livod::sim
