#pragma once
// Estimator settings that fit the sensor (issue 15): the LiDAR's model facts (beams, points per
// scan, range noise, beam divergence) decide the point selection and the noise model, so that the
// configuration `livod sim` writes - no `estimator:` section - runs in real time at full accuracy
// on every model. A key the file sets is never touched. check-config prints each effective value
// with its reason.
//
// One table of model facts lives in estimator_defaults.cpp (kLidarModelFacts) and one function
// turns facts into parameters (estimator_settings_for). When the LiDAR families get their model
// descriptor tables, lidar_model_facts() becomes a lookup into them; a new model (Hesai, ...)
// needs one row with its datasheet figures and nothing else.

#include <optional>
#include <set>
#include <string>
#include <string_view>
#include <vector>

#include "daemon/config/config.hpp"
#include "estimator/params.hpp"

namespace livod::daemon {

// What the estimator defaults need to know about a LiDAR model, from its datasheet.
struct LidarModelFacts {
  std::string_view model;        // canonical name (SensorConfig::model)
  int beams = 0;                 // rings (Livox: lasers / lines)
  double points_per_scan = 0.0;  // single return, default mode (10 Hz scans)
  double range_sigma_m = 0.0;    // range noise, 1 sigma, of a strong return
  double divergence_deg = 0.0;   // beam divergence (FWHM) of the wider axis
  std::string_view source;       // where the figures come from
};

// The facts of a model, or nullopt when the table has no row for it.
std::optional<LidarModelFacts> lidar_model_facts(std::string_view model);

// The estimator settings for a model (nullopt facts: a model the table does not know) with the
// reason for each, applied to `params` except for the keys in `given` ("lio.point_filter_num",
// ...), which the configuration set.
std::vector<EstimatorChoice> estimator_settings_for(const std::optional<LidarModelFacts>& facts,
                                                    std::string_view model,
                                                    const std::set<std::string>& given,
                                                    estimator::EstimatorParams& params);

// The LiDAR the estimator runs on: the body IMU's own LiDAR when the body is an internal IMU, else
// the first enabled LiDAR; -1 when there is none.
int estimator_lidar_index(const LivodConfig& config);

// Applies estimator_settings_for() for the configuration's estimator LiDAR to config.estimator and
// records the choices in config.estimator_choices.
void apply_estimator_defaults(LivodConfig& config);

// Per-scan points the update works on (lio.point_budget) and the raw points per scan the point
// filter keeps at most (lio.point_filter_num): the budget that keeps a frame within the real-time
// target on the reference machine (docs/estimator.md, "Defaults per sensor").
inline constexpr int kDefaultPointBudget = 8000;
inline constexpr double kRawPointsPerScan = 35000.0;

}  // namespace livod::daemon
