#include "tools/sim/lidar_return.hpp"

#include <algorithm>
#include <array>
#include <cmath>

namespace livod::sim {
namespace {

constexpr double kRayStart = 1e-3;         // m: the window, not the sensor's own housing
constexpr double kLeaveSurface = 1e-4;     // m: restart a ray just past a surface
constexpr double kReferenceRho = 0.8;      // datasheets' "range at 80 %"
constexpr double kMinIncidenceCos = 0.02;  // grazing echoes still carry some signal
constexpr int kMaxFoliageLayers = 4;       // crowns a beam can cross before it is lost

struct Echo {
  double range = 0.0;
  double reflectivity = 0.0;
  double incidence_cos = 0.0;
};

// One ray: the first solid it meets, or the leaf it ends on inside foliage (a volume whose
// surface has foliage_free_path_m > 0: the beam travels an exponential depth inside, and leaves
// the volume if that depth is beyond its far side).
bool cast_ray(const SceneContext& scene, double time, const Eigen::Vector3d& origin,
              const Eigen::Vector3d& dir, double max_range, std::mt19937_64& rng, Echo& echo) {
  std::uniform_real_distribution<double> unit(0.0, 1.0);
  double start = kRayStart;
  for (int layer = 0; layer < kMaxFoliageLayers; ++layer) {
    Hit hit;
    if (!scene.intersect(time, origin, dir, start, max_range, hit)) return false;
    const double free_path = hit.surface->foliage_free_path_m;
    if (free_path <= 0.0) {
      echo = Echo{hit.range, hit.surface->reflectivity, std::abs(hit.normal.dot(dir))};
      return true;
    }
    const double depth = -free_path * std::log(1.0 - unit(rng));
    // Leaves face every way: the echo's incidence is that of a random orientation.
    const double leaf_cos = unit(rng);
    Hit next;
    const bool more =
        scene.intersect(time, origin, dir, hit.range + kLeaveSurface, max_range, next);
    if (!more || hit.range + depth < next.range) {
      if (hit.range + depth > max_range) return false;
      echo = Echo{hit.range + depth, hit.surface->reflectivity, leaf_cos};
      return true;
    }
    if (next.surface->foliage_free_path_m <= 0.0) {  // a trunk or wall inside / behind the crown
      echo = Echo{next.range, next.surface->reflectivity, std::abs(next.normal.dot(dir))};
      return true;
    }
    start = next.range + kLeaveSurface;  // left the volume (or entered the next): go on
  }
  return false;
}

}  // namespace

LidarReturn measure_return(const SceneContext& scene, double time, const Eigen::Vector3d& origin,
                           const Eigen::Vector3d& dir, const Eigen::Vector3d& up,
                           const RangeModel& model, std::mt19937_64& rng) {
  LidarReturn out;
  // Sub-rays over the footprint: the centre and the two half-maximum points of a Gaussian beam
  // along the footprint's long axis, weighted 1 and 1/2 (three rays, not five: ray casting is the
  // simulator's cost, and the long axis is where a footprint straddles edges and smears).
  struct Ray {
    Eigen::Vector3d dir;
    double weight;
  };
  std::array<Ray, 3> rays{Ray{dir, 1.0}, {}, {}};
  int n_rays = 1;
  if (model.divergence_h_rad > 0.0 || model.divergence_v_rad > 0.0) {
    Eigen::Vector3d across = dir.cross(up);
    if (across.squaredNorm() < 1e-12) across = dir.unitOrthogonal();
    across.normalize();
    const bool wide = model.divergence_h_rad >= model.divergence_v_rad;
    const Eigen::Vector3d axis = wide ? across : Eigen::Vector3d(across.cross(dir));
    const double half = 0.5 * (wide ? model.divergence_h_rad : model.divergence_v_rad);
    rays[1] = {(dir + half * axis).normalized(), 0.5};
    rays[2] = {(dir - half * axis).normalized(), 0.5};
    n_rays = 3;
  }
  struct SubEcho {
    Echo echo;
    double energy;  // weight x rho cos / r^2: what the detector receives from this sub-ray
    double weight;
  };
  std::array<SubEcho, 3> echoes{};
  int n_echoes = 0;
  double total_weight = 0.0;
  for (int i = 0; i < n_rays; ++i) {
    total_weight += rays[static_cast<std::size_t>(i)].weight;
    Echo e;
    if (!cast_ray(scene, time, origin, rays[static_cast<std::size_t>(i)].dir, model.max_range_m,
                  rng, e)) {
      continue;
    }
    const double w = rays[static_cast<std::size_t>(i)].weight;
    const double r = std::max(e.range, 0.1);
    echoes[static_cast<std::size_t>(n_echoes++)] =
        SubEcho{e, w * e.reflectivity * std::max(e.incidence_cos, kMinIncidenceCos) / (r * r), w};
  }
  if (n_echoes == 0) return out;
  // Echoes closer than a pulse length merge (one broadened pulse: a mixed pixel between two
  // surfaces, a smeared range on an inclined one); separate pulses compete and the strongest is
  // reported (single-return sensors in strongest mode).
  for (int i = 1; i < n_echoes; ++i) {  // insertion sort by range (at most three)
    for (int k = i; k > 0 && echoes[static_cast<std::size_t>(k)].echo.range <
                                 echoes[static_cast<std::size_t>(k - 1)].echo.range;
         --k) {
      std::swap(echoes[static_cast<std::size_t>(k)], echoes[static_cast<std::size_t>(k - 1)]);
    }
  }
  double best_energy = -1.0;
  double range = 0.0, range2 = 0.0, rho = 0.0, cosine = 0.0, signal = 0.0;
  for (int begin = 0; begin < n_echoes;) {
    int end = begin + 1;
    while (end < n_echoes && echoes[static_cast<std::size_t>(end)].echo.range -
                                     echoes[static_cast<std::size_t>(end - 1)].echo.range <
                                 model.pulse_length_m) {
      ++end;
    }
    double energy = 0.0, er = 0.0, er2 = 0.0, erho = 0.0, ecos = 0.0, s = 0.0;
    for (int k = begin; k < end; ++k) {
      const SubEcho& e = echoes[static_cast<std::size_t>(k)];
      energy += e.energy;
      er += e.energy * e.echo.range;
      er2 += e.energy * e.echo.range * e.echo.range;
      erho += e.energy * e.echo.reflectivity;
      ecos += e.energy * e.echo.incidence_cos;
      s += e.weight * e.echo.reflectivity * std::max(e.echo.incidence_cos, kMinIncidenceCos);
    }
    if (energy > best_energy) {
      best_energy = energy;
      range = er / energy;
      range2 = er2 / energy;
      rho = erho / energy;
      cosine = ecos / energy;
      signal = s / total_weight;  // the beam's returned fraction: rho cos of a full hit
    }
    begin = end;
  }
  const double spread = std::sqrt(std::max(0.0, range2 - range * range));
  // Signal-limited detection and the noise and bias that grow towards the limit.
  const double limit = model.max_range_m * std::sqrt(std::max(signal, 0.0) / kReferenceRho);
  const double q = limit > 0.0 ? range / limit : 1e9;
  if (model.detection_limited && q > 1.0) return out;
  const double sigma =
      std::sqrt(model.sigma_m * model.sigma_m +
                std::pow(model.sigma_at_limit_m * std::pow(q, 1.2), 2) + spread * spread);
  const double bias = model.detection_limited ? model.intensity_bias_m * std::min(q * q, 1.0) : 0.0;
  std::normal_distribution<double> normal(0.0, 1.0);
  std::uniform_real_distribution<double> unit(0.0, 1.0);
  const double measured = range + bias + sigma * normal(rng);
  if (unit(rng) < model.dropout_probability) return out;
  if (measured < model.min_range_m || measured > model.max_range_m) return out;
  out.valid = true;
  out.range_m = measured;
  out.true_range_m = range;
  out.reflectivity = rho;
  out.incidence_cos = cosine;
  return out;
}

}  // namespace livod::sim
