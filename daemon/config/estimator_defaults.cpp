#include "daemon/config/estimator_defaults.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <numbers>
#include <sstream>
#include <type_traits>

#include "drivers/lidar_family.hpp"

namespace livod::daemon {
namespace {

// The 1-sigma range noise and the divergence the estimator uses where the family tables
// (drivers/<family>/<family>_family.cpp) have only an accuracy bound (Velodyne "+-3 cm typical")
// or nothing (Ouster: "differ by hardware revision"). Everything else comes from the family row.
struct NoiseFacts {
  std::string_view model;
  double range_sigma_m;
  double divergence_deg;  // 0: take the family table's
  std::string_view source;
};
constexpr std::array<NoiseFacts, 5> kNoiseFacts{{
    {"OS1-64", 0.015, 0.13, "Ouster OS1 datasheet: 1.5 cm at high SNR, 0.13 deg FWHM"},
    {"OS1-128", 0.015, 0.18, "Ouster OS1 datasheet: 1.5 cm at high SNR, 0.18 deg FWHM"},
    {"VLP-16", 0.015, 0.17, "Velodyne VLP-16: +-3 cm typical (1.5 cm sigma), 3 mrad divergence"},
    {"HDL-32E", 0.01, 0.17, "Velodyne HDL-32E: < 2 cm (1 cm sigma), 3 mrad divergence"},
    {"MID-360", 0.02, 0.2, "Livox Mid-360: 2 cm (10 m), divergence assumed 0.2 deg"},
}};

std::string number(double v) {
  std::ostringstream os;
  os << v;
  return os.str();
}

bool enabled_lidar(const SensorConfig& s) {
  return s.enabled && sensor_kind(s.driver) == SensorKind::lidar;
}

// A sparse spinning LiDAR beside a denser one that builds the map is matched only: its rings cut
// voxels in single-ring lines, planes whose tilt about the line nothing observes, and the pair
// matches those (docs/estimator.md "Several LiDARs": a VLP-16 beside an Avia on the realistic
// street 17.4 mm building the map, 5.1 mm matched only, the Avia alone 7.2 mm). A LiDAR without
// model facts is never taken for the denser one (a generic Ouster "OS" may have 16 rings).
void match_sparse_beside_dense(LivodConfig& config) {
  std::vector<SensorConfig*> sparse;  // those whose file leaves build_map to the default
  bool dense_builds_map = false;
  for (SensorConfig& s : config.sensors) {
    if (!enabled_lidar(s)) continue;
    const auto facts = lidar_model_facts(s.model);
    if (sparse_spinning(facts)) {
      if (!s.lio_build_map_given) sparse.push_back(&s);
    } else if (facts && s.lio.build_map) {
      dense_builds_map = true;
    }
  }
  if (!dense_builds_map) return;
  for (SensorConfig* s : sparse) {
    s->lio.build_map = false;
    s->lio_from_model.insert("build_map");
  }
}

// A matched-only LiDAR's rows are gated at kMatchedOnlyGateSigmas: they meet planes another LiDAR
// fitted from its own viewpoint and cannot refine them, and on the VLP-16 + Avia street the rows
// that land between 2 and 3 sigma off those planes (most in the tree crowns) pull the pair away:
// seeds 1-5 6.7 -> 5.2 mm mean against the Avia alone's 7.2 (docs/estimator.md "Several LiDARs").
// Not where the file sets sigma_num (its lio: or estimator.lio).
void gate_matched_only(LivodConfig& config) {
  if (config.estimator_given.contains("lio.sigma_num")) return;
  for (SensorConfig& s : config.sensors) {
    if (!enabled_lidar(s) || s.lio.build_map || s.lio.sigma_num) continue;
    s.lio.sigma_num = kMatchedOnlyGateSigmas;
    s.lio_from_model.insert("sigma_num");
  }
}

// The settings of how the map is built follow the model of a LiDAR that builds it: when the
// estimator LiDAR is matched only (a VLP-16 beside an Avia), the map is the other LiDAR's, and the
// VLP-16's pose term in the map points cost the street pair what the Avia alone does not pay
// (docs/estimator.md "Several LiDARs": seeds 1-5 8.4 / 8.4 / 11.4 / 24.8 / 7.9 mm with the
// VLP-16's choice, 6.8 / 8.2 / 8.3 / 6.8 / 7.4 mm with the Avia's).
void follow_the_map_builder(LivodConfig& config, int lidar,
                            const estimator::EstimatorParams& file_values) {
  const SensorConfig& own = config.sensors[static_cast<std::size_t>(lidar)];
  if (own.lio.build_map) return;
  for (const SensorConfig& s : config.sensors) {
    if (!enabled_lidar(s) || !s.lio.build_map) continue;
    const auto facts = lidar_model_facts(s.model);
    if (!facts) continue;
    estimator::EstimatorParams builder = file_values;
    const auto choices = estimator_settings_for(facts, s.model, config.estimator_given, builder);
    const std::string why = " (" + s.name + " builds the map; " + own.name + " is matched only)";
    for (const EstimatorChoice& from : choices) {
      if (config.estimator_given.contains(from.key)) continue;
      if (from.key == "lio.map_pose_covariance") {
        config.estimator.lio.map_pose_covariance = builder.lio.map_pose_covariance;
      } else if (from.key == "lio.min_plane_spread_ratio") {
        config.estimator.lio.min_plane_spread_ratio = builder.lio.min_plane_spread_ratio;
      } else if (from.key == "lio.map_min_move_m") {
        // The gate holds back scans of the LiDARs that build the map: theirs is the view.
        config.estimator.lio.map_min_move_m = builder.lio.map_min_move_m;
      } else {  // the point model is per LiDAR
        continue;
      }
      for (EstimatorChoice& c : config.estimator_choices) {
        if (c.key != from.key) continue;
        c.value = from.value;
        c.reason = from.reason + why;
      }
    }
    return;
  }
}

}  // namespace

std::optional<LidarModelFacts> lidar_model_facts(std::string_view model) {
  const auto match = drivers::find_model(model);
  if (!match || match->model->points_per_second <= 0.0 || match->model->scan_rate_hz <= 0.0) {
    return std::nullopt;
  }
  const drivers::LidarModelInfo& info = *match->model;
  LidarModelFacts f;
  f.model = std::string(info.name);
  f.beams = info.beams;
  // A spinning LiDAR's scans can be cut at an azimuth or by its own frame counter; Livox's
  // rosette only by time.
  f.spinning = match->family->allows(drivers::CutMode::kAzimuth) ||
               match->family->allows(drivers::CutMode::kFrameId);
  f.scan_rate_hz = info.scan_rate_hz;
  f.points_per_scan = info.points_per_second / info.scan_rate_hz;
  f.source = std::string(match->family->vendor) + " datasheet, livod's " +
             std::string(match->family->driver) + " model table";
  const auto noise = std::find_if(kNoiseFacts.begin(), kNoiseFacts.end(),
                                  [&](const NoiseFacts& n) { return n.model == info.name; });
  if (noise != kNoiseFacts.end()) {
    f.range_sigma_m = noise->range_sigma_m;
    f.divergence_deg = noise->divergence_deg;
    f.source = std::string(noise->source);
  } else if (info.range_noise_m) {
    f.range_sigma_m = *info.range_noise_m;
  } else {
    f.range_sigma_m = estimator::LioParams{}.dept_err;
    f.source += "; no range noise in livod's sources: FAST-LIVO2's";
  }
  if (f.divergence_deg <= 0.0) {
    if (info.beam_divergence_rad) {
      f.divergence_deg = *info.beam_divergence_rad * 180.0 / std::numbers::pi;
    } else {
      f.divergence_deg = kAssumedDivergenceDeg;
      f.divergence_assumed = true;
    }
  }
  return f;
}

std::vector<EstimatorChoice> estimator_settings_for(const std::optional<LidarModelFacts>& facts,
                                                    std::string_view model,
                                                    const std::set<std::string>& given,
                                                    estimator::EstimatorParams& params) {
  auto& lio = params.lio;
  std::vector<EstimatorChoice> choices;
  // A key of the file wins; anything else is set here and explained. Values as the file writes
  // them.
  const auto text = [](auto v) -> std::string {
    if constexpr (std::is_same_v<decltype(v), bool>) {
      return v ? "true" : "false";
    } else {
      return number(static_cast<double>(v));
    }
  };
  const auto choose = [&](const char* key, auto& field, auto value, const std::string& reason) {
    if (given.contains(key)) {
      choices.push_back({key, text(field), "set in the configuration"});
      return;
    }
    field = value;
    choices.push_back({key, text(field), reason});
  };
  // A value left as the file or the estimator has it, explained.
  const auto keep = [&](const char* key, auto field, const std::string& reason) {
    choices.push_back(
        {key, text(field), given.contains(key) ? std::string("set in the configuration") : reason});
  };
  const std::string name = model.empty() ? std::string("unknown model") : std::string(model);
  // The plane spread test compares a plane's spread with its points' covariances, which must then
  // be their sensor noise: the pose term is common to a scan and spreads nothing.
  const bool spread_given =
      given.contains("lio.min_plane_spread_ratio") && lio.min_plane_spread_ratio > 0.0;
  // The pose term's value and reason for this model, unless the file sets the spread test.
  const auto choose_pose_term = [&](bool value, const std::string& reason) {
    choose("lio.map_pose_covariance", lio.map_pose_covariance, value && !spread_given,
           spread_given ? "lio.min_plane_spread_ratio is set: map points carry their sensor noise "
                          "only (the spread test compares with it)"
                        : reason);
  };

  // The update's cost per frame follows the points it works on: a fixed budget per scan, whatever
  // the sensor and the place, is what keeps every model real-time (lio/point_budget.hpp).
  choose("lio.point_budget", lio.point_budget, kDefaultPointBudget,
         "points per scan the update works on: the downsampling cell grows above "
         "filter_size_surf until a scan fits (real time on every sensor)");
  choose("lio.filter_size_surf", lio.filter_size_surf, 0.1,
         "smallest downsampling cell (FAST-LIVO2); the point budget grows it where a scan has more "
         "points");
  // A plane seen again and again (a near wall, the road) averages the range noise of many scans
  // instead of freezing on its first 50 points, at a frozen node's memory past the stored ones
  // (map/voxel_map.hpp): no model lost accuracy, the corridor pair and the streets gained
  // (docs/estimator.md "Map").
  choose("lio.max_points_num", lio.max_points_num, kDefaultPlanePoints,
         "points a plane refines on before it freezes (FAST-LIVO2: 50; past max_cov_points from "
         "their moments)");
  if (!facts) {
    choose("lio.point_filter_num", lio.point_filter_num, 1,
           name + " has no model facts: every point, the point budget bounds the cost");
    const std::string no_facts = name + " has no model facts: ";
    keep("lio.dept_err", lio.dept_err, no_facts + "FAST-LIVO2's range noise");
    keep("lio.beam_err_deg", lio.beam_err_deg, no_facts + "FAST-LIVO2's bearing noise");
    choose_pose_term(lio.map_pose_covariance,
                     no_facts + "FAST-LIVO2's (map points carry the pose uncertainty)");
    keep("lio.min_plane_spread_ratio", lio.min_plane_spread_ratio,
         no_facts + "FAST-LIVO2's planarity test alone");
    keep("lio.map_min_move_m", lio.map_min_move_m,
         no_facts + "every scan goes into the map (FAST-LIVO2)");
    return choices;
  }
  // Undistortion and downsampling cost per raw point: keep one point in n (alike in every ring,
  // lio/point_filter.hpp) so that a scan brings at most about kRawPointsPerScan.
  const int stride =
      std::max(1, static_cast<int>(std::lround(facts->points_per_scan / kRawPointsPerScan)));
  std::ostringstream why_stride;
  why_stride << name << " brings " << facts->points_per_scan << " points per "
             << facts->scan_rate_hz << " Hz scan; one point in " << stride
             << (stride > 1 ? " (alike in every ring)" : "") << " keeps about "
             << std::lround(facts->points_per_scan / stride);
  choose("lio.point_filter_num", lio.point_filter_num, stride, why_stride.str());
  // The noise model of the points: the datasheet's range noise, and a bearing noise of half the
  // beam divergence (the footprint's half width: where in it the echo comes from is unknown).
  choose("lio.dept_err", lio.dept_err, std::max(0.01, facts->range_sigma_m),
         name + " range noise " + number(facts->range_sigma_m) + " m (" +
             std::string(facts->source) + ")");
  choose("lio.beam_err_deg", lio.beam_err_deg, std::max(0.05, 0.5 * facts->divergence_deg),
         "half the beam divergence of " + number(facts->divergence_deg) + " deg" +
             (facts->divergence_assumed
                  ? " (not in livod's sources for " + name + ": a spinning LiDAR's 3 mrad assumed)"
                  : std::string()));
  // Few rings (kFewRings) see most voxels in single rings. The pose uncertainty at insertion,
  // common to a scan, added to each map point weights far planes less: that tilts a long drive
  // (docs/estimator.md "Long drives") but keeps such a LiDAR's single-ring lines weak and its
  // street on track. Denser rings span their voxels: their lines are kept out of the planes by
  // the spread test instead, which needs points with their sensor noise only.
  const bool few_rings = spinning_with_fewer_rings(facts, kFewRings);
  const std::string rings = std::to_string(facts->beams) + " rings";
  // "OS1-128 has 128 rings" / "AVIA scans a dense rosette"
  const std::string scans = name + (facts->spinning ? " has " + rings : " scans a dense rosette");
  choose_pose_term(few_rings,
                   few_rings ? name + "'s " + rings +
                                   ": map points carry the pose uncertainty (its single-ring lines "
                                   "stay weak; a street drive without it loses track)"
                             : scans +
                                   ": map points carry their sensor noise only (the pose term "
                                   "tilts long drives)");
  // One ring's hits across a voxel look flat under range noise (a plane through the sensor):
  // not planes (estimator/map/plane.hpp; the OS1-128 street 19.5 -> 11.6 mm, the HDL-32E's
  // 21.4 -> 9.9 mm). Livox's rosette draws no rings: measured no better (the Avia room 13.8 ->
  // 15.5 mm over 6 seeds), so off.
  const bool spanning = facts->spinning && !few_rings && !lio.map_pose_covariance;
  std::string spread_reason;
  if (spanning) {
    spread_reason = scans + ": a plane's points must spread at least twice their noise sigma " +
                    "along its narrower direction (one ring's hits are a line, not a plane)";
  } else if (few_rings) {
    spread_reason = name + "'s " + rings + ": off (most voxels hold one ring: without them too " +
                    "few planes are left, and the realistic VLP-16 street loses track)";
  } else if (lio.map_pose_covariance) {
    spread_reason =
        "lio.map_pose_covariance is set: off (the test compares a plane's spread with "
        "its points' noise, and the pose term is not noise)";
  } else {
    spread_reason = scans + ": off (FAST-LIVO2's planarity test alone; no gain measured)";
  }
  choose("lio.min_plane_spread_ratio", lio.min_plane_spread_ratio,
         spanning ? kPlaneSpreadRatio : 0.0, spread_reason);
  // Few rings see a street's ground in single rings at fixed ranges: inserted scan after scan from
  // one place, the sensor's systematic range errors become planes that move with it, and once it
  // drives off, the map holds it back (the VLP-16 street: lost at 100 m -> 47 mm).
  const std::string gated = name + "'s " + rings + ": a scan goes into the map only after the " +
                            "sensor moved " + number(kViewpointMoveM) +
                            " m or turned lio.map_min_turn_deg (standing still, the same view " +
                            "bends the map)";
  const std::string every = scans + ": every scan goes into the map (FAST-LIVO2)";
  choose("lio.map_min_move_m", lio.map_min_move_m, few_rings ? kViewpointMoveM : 0.0,
         few_rings ? gated : every);
  return choices;
}

int estimator_lidar_index(const LivodConfig& config) {
  if (config.body_is_internal_imu) return config.body_sensor_index;
  for (std::size_t i = 0; i < config.sensors.size(); ++i) {
    if (enabled_lidar(config.sensors[i])) return static_cast<int>(i);
  }
  return -1;
}

void apply_estimator_defaults(LivodConfig& config) {
  const int lidar = estimator_lidar_index(config);
  if (lidar < 0) return;
  const std::string& model = config.sensors[static_cast<std::size_t>(lidar)].model;
  const estimator::EstimatorParams file_values = config.estimator;
  config.estimator_choices = estimator_settings_for(lidar_model_facts(model), model,
                                                    config.estimator_given, config.estimator);
  // The other LiDARs: their own model's point model, not the estimator LiDAR's (a VLP-16's
  // bearing noise on an Avia's points, or a VLP-16's every point on an OS1-128 beside it).
  for (std::size_t i = 0; i < config.sensors.size(); ++i) {
    SensorConfig& s = config.sensors[i];
    if (static_cast<int>(i) == lidar || !enabled_lidar(s)) continue;
    const auto facts = lidar_model_facts(s.model);
    if (!facts) continue;  // no facts: estimator.lio's values, as the file gives none
    estimator::EstimatorParams own = file_values;
    estimator_settings_for(facts, s.model, config.estimator_given, own);
    const auto fill = [&](const char* key, auto& field, auto value) {
      if (field || config.estimator_given.contains(std::string("lio.") + key)) return;
      field = value;
      s.lio_from_model.insert(key);
    };
    fill("dept_err", s.lio.dept_err, own.lio.dept_err);
    fill("beam_err_deg", s.lio.beam_err_deg, own.lio.beam_err_deg);
    fill("point_filter_num", s.lio.point_filter_num, own.lio.point_filter_num);
  }
  match_sparse_beside_dense(config);
  follow_the_map_builder(config, lidar, file_values);
  gate_matched_only(config);
}

}  // namespace livod::daemon
