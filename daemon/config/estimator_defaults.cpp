#include "daemon/config/estimator_defaults.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <sstream>

namespace livod::daemon {
namespace {

// The model facts. One row per LiDAR model the daemon decodes and the simulator simulates; a model
// without a row gets the generic defaults (a point budget, FAST-LIVO2's noise model) and
// check-config says so. Hesai rows go here (model name as SensorConfig::model spells it).
constexpr std::array<LidarModelFacts, 6> kLidarModelFacts{{
    {"OS1-64", 64, 65536.0, 0.015, 0.13,
     "Ouster OS1 datasheet: 1024 x 64 per 10 Hz scan, 1.5 cm at high SNR, 0.13 deg FWHM"},
    {"OS1-128", 128, 131072.0, 0.015, 0.18,
     "Ouster OS1 datasheet: 1024 x 128 per 10 Hz scan, 1.5 cm at high SNR, 0.18 deg FWHM"},
    {"VLP-16", 16, 28800.0, 0.015, 0.17,
     "Velodyne VLP-16: 16 x 1800 per 10 Hz revolution, +-3 cm typical, 3 mrad divergence"},
    {"HDL-32E", 32, 69400.0, 0.01, 0.17,
     "Velodyne HDL-32E: 32 x 2170 per 10 Hz revolution, < 2 cm, 3 mrad divergence"},
    {"AVIA", 6, 24000.0, 0.02, 0.28,
     "Livox Avia: 240 kpoints/s, 2 cm (20 m), 0.28 x 0.03 deg divergence"},
    {"MID-360", 4, 20000.0, 0.02, 0.2,
     "Livox Mid-360: 200 kpoints/s, 2 cm (10 m), divergence assumed 0.2 deg"},
}};

std::string number(double v) {
  std::ostringstream os;
  os << v;
  return os.str();
}

}  // namespace

std::optional<LidarModelFacts> lidar_model_facts(std::string_view model) {
  for (const auto& f : kLidarModelFacts) {
    if (f.model == model) return f;
  }
  return std::nullopt;
}

std::vector<EstimatorChoice> estimator_settings_for(const std::optional<LidarModelFacts>& facts,
                                                    std::string_view model,
                                                    const std::set<std::string>& given,
                                                    estimator::EstimatorParams& params) {
  auto& lio = params.lio;
  std::vector<EstimatorChoice> choices;
  // A key of the file wins; anything else is set here and explained.
  const auto choose = [&](const char* key, auto& field, auto value, const std::string& reason) {
    if (given.contains(key)) {
      choices.push_back({key, number(static_cast<double>(field)), "set in the configuration"});
      return;
    }
    field = value;
    choices.push_back({key, number(static_cast<double>(field)), reason});
  };
  const std::string name = model.empty() ? std::string("unknown model") : std::string(model);

  // The update's cost per frame follows the points it works on: a fixed budget per scan, whatever
  // the sensor and the place, is what keeps every model real-time (lio/point_budget.hpp).
  choose("lio.point_budget", lio.point_budget, kDefaultPointBudget,
         "points per scan the update works on: the downsampling cell grows above "
         "filter_size_surf until a scan fits (real time on every sensor)");
  choose("lio.filter_size_surf", lio.filter_size_surf, 0.1,
         "smallest downsampling cell (FAST-LIVO2); the point budget grows it where a scan has more "
         "points");
  if (!facts) {
    choose("lio.point_filter_num", lio.point_filter_num, 1,
           name + " is not in the model table: every point, the point budget bounds the cost");
    choices.push_back({"lio.dept_err", number(lio.dept_err),
                       given.contains("lio.dept_err")
                           ? "set in the configuration"
                           : name + " is not in the model table: FAST-LIVO2's range noise"});
    choices.push_back({"lio.beam_err_deg", number(lio.beam_err_deg),
                       given.contains("lio.beam_err_deg")
                           ? "set in the configuration"
                           : name + " is not in the model table: FAST-LIVO2's bearing noise"});
    return choices;
  }
  // Undistortion and downsampling cost per raw point: keep every n-th point of each ring so that a
  // scan brings at most about kRawPointsPerScan.
  const int stride =
      std::max(1, static_cast<int>(std::lround(facts->points_per_scan / kRawPointsPerScan)));
  std::ostringstream why_stride;
  why_stride << name << " brings " << facts->points_per_scan << " points per 10 Hz scan; every "
             << stride << (stride == 1 ? "" : "th") << " point of each ring keeps about "
             << std::lround(facts->points_per_scan / stride);
  choose("lio.point_filter_num", lio.point_filter_num, stride, why_stride.str());
  // The noise model of the points: the datasheet's range noise, and a bearing noise of half the
  // beam divergence (the footprint's half width: where in it the echo comes from is unknown).
  choose("lio.dept_err", lio.dept_err, std::max(0.01, facts->range_sigma_m),
         name + " range noise " + number(facts->range_sigma_m) + " m (" +
             std::string(facts->source) + ")");
  choose("lio.beam_err_deg", lio.beam_err_deg, std::max(0.05, 0.5 * facts->divergence_deg),
         "half the beam divergence of " + number(facts->divergence_deg) + " deg");
  return choices;
}

int estimator_lidar_index(const LivodConfig& config) {
  if (config.body_is_internal_imu) return config.body_sensor_index;
  for (std::size_t i = 0; i < config.sensors.size(); ++i) {
    const auto& s = config.sensors[i];
    if (s.enabled && sensor_kind(s.driver) == SensorKind::lidar) return static_cast<int>(i);
  }
  return -1;
}

void apply_estimator_defaults(LivodConfig& config) {
  const int lidar = estimator_lidar_index(config);
  if (lidar < 0) return;
  const std::string& model = config.sensors[static_cast<std::size_t>(lidar)].model;
  config.estimator_choices = estimator_settings_for(lidar_model_facts(model), model,
                                                    config.estimator_given, config.estimator);
}

}  // namespace livod::daemon
