#pragma once
// Estimator settings that fit the sensor (issue 15): the LiDAR's model facts (beams, points per
// scan, range noise, beam divergence) decide the point selection and the noise model, so that the
// configuration `livod sim` writes - no `estimator:` section - runs in real time at full accuracy
// on every model. A key the file sets is never touched. check-config prints each effective value
// with its reason.
//
// The model facts come from the LiDAR families' model tables (drivers/lidar_family.hpp: beams,
// points per second, scan rate, datasheet range error and divergence), which every decoded model
// has; a short table in estimator_defaults.cpp adds the 1-sigma range noise and divergence where a
// family table has only an accuracy bound or nothing. One function turns facts into parameters
// (estimator_settings_for). A new model gets its defaults from its family row.

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
  std::string model;                // canonical name (SensorConfig::model)
  int beams = 0;                    // rings (Livox: lasers / lines)
  double points_per_scan = 0.0;     // single return, default mode (default scan rate)
  double scan_rate_hz = 10.0;       // the default scan rate points_per_scan refers to
  double range_sigma_m = 0.0;       // range noise, 1 sigma, of a strong return
  double divergence_deg = 0.0;      // beam divergence (FWHM) of the wider axis
  bool divergence_assumed = false;  // no source gives it: kAssumedDivergenceDeg
  bool spinning = false;            // rings at fixed elevations (not Livox's rosette)
  std::string source;               // where the figures come from
};

// Beam divergence of a model whose sources give none: the Velodyne manuals' 3 mrad of a spinning
// LiDAR's wider axis (VLS-128 manual table F-1).
inline constexpr double kAssumedDivergenceDeg = 0.17;

// The facts of a model (any family's canonical name or alias), or nullopt when no family table
// knows it or its row has no point rate (Ouster's generic "OS": the metadata tells).
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
// records the choices in config.estimator_choices. With several LiDARs each other LiDAR's point
// model (dept_err, beam_err_deg, point_filter_num) follows its own model the same way: set in its
// `lio:` section, unless the file sets the key in its own lio: or in estimator.lio (then that
// value holds for it, as without defaults). The point budget is one for the estimator: it counts
// the points of every LiDAR in an update (docs/estimator.md "Several LiDARs").
// A sparse spinning LiDAR (sparse_spinning) beside a LiDAR that is not and builds the map is
// matched only (lio.build_map false) unless its own lio: sets build_map. When the estimator LiDAR
// is then matched only, how the map is built (lio.map_pose_covariance, lio.min_plane_spread_ratio)
// follows the first LiDAR that builds it, and its reason says so. A matched-only LiDAR's rows are
// gated at kMatchedOnlyGateSigmas unless the file sets sigma_num (its lio: or estimator.lio).
void apply_estimator_defaults(LivodConfig& config);

// Per-scan points the update works on (lio.point_budget) and the raw points per scan the point
// filter keeps at most (lio.point_filter_num): the budget that keeps a frame within the real-time
// target on the reference machine (docs/estimator.md, "Defaults per sensor").
inline constexpr int kDefaultPointBudget = 8000;
inline constexpr double kRawPointsPerScan = 35000.0;
// Points a map plane refines on before it freezes (lio.max_points_num; FAST-LIVO2's 50): about
// 0.9 mm of plane offset noise instead of 2.8 mm under 2 cm of range noise (docs/estimator.md
// "Map").
inline constexpr int kDefaultPlanePoints = 500;
// A spinning LiDAR with fewer rings than this, beside a denser LiDAR that builds the map, is
// matched only (apply_estimator_defaults; docs/estimator.md "Several LiDARs").
inline constexpr int kDenseRings = 64;
// The association gate of a matched-only LiDAR's rows, in sigmas (the map's is lio.sigma_num, 3).
inline constexpr double kMatchedOnlyGateSigmas = 2.0;

// Spinning LiDARs with fewer rings than this (the VLP-16) see most map voxels in single rings.
// Their map points carry the pose uncertainty (lio.map_pose_covariance), which keeps those
// single-ring lines weak, and a scan goes into the map only from a new viewpoint
// (lio.map_min_move_m = kViewpointMoveM; estimator/map/insert_gate.hpp): the realistic VLP-16
// street lost track without either. Models with more rings, and Livox, insert points with their
// sensor noise only (the pose term tilts long drives), and spinning ones keep single-ring lines
// out of the planes instead (lio.min_plane_spread_ratio = kPlaneSpreadRatio). Measured:
// docs/estimator.md "Long drives", "Map insertion from new viewpoints", "Lines are not planes".
inline constexpr int kFewRings = 32;
inline constexpr double kViewpointMoveM = 0.5;
// The points of a plane spread at least twice their noise sigma along its narrower direction.
inline constexpr double kPlaneSpreadRatio = 4.0;

// A spinning LiDAR with fewer than `rings` rings (false without facts: nothing is known).
inline bool spinning_with_fewer_rings(const std::optional<LidarModelFacts>& facts, int rings) {
  return facts && facts->spinning && facts->beams > 0 && facts->beams < rings;
}

// A spinning LiDAR with fewer than kDenseRings rings.
inline bool sparse_spinning(const std::optional<LidarModelFacts>& facts) {
  return spinning_with_fewer_rings(facts, kDenseRings);
}

}  // namespace livod::daemon
