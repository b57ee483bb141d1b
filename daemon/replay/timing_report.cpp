#include "daemon/replay/timing_report.hpp"

#include <fmt/core.h>
#include <sys/resource.h>
#include <unistd.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <numeric>

#include "core/error.hpp"
#include "daemon/replay/trajectory_writer.hpp"

namespace livod::daemon::replay {
namespace {

constexpr double kMiB = 1024.0 * 1024.0;

double rank(const std::vector<float>& sorted, double q) {
  // Nearest rank: the smallest value with at least q of the values at or below it.
  const auto n = static_cast<double>(sorted.size());
  const auto k = static_cast<std::size_t>(std::max(1.0, std::ceil(q * n)));
  return sorted[std::min(k, sorted.size()) - 1];
}

std::string json_string(const std::string& s) {
  std::string out = "\"";
  for (const char c : s) {
    switch (c) {
      case '"':
        out += "\\\"";
        break;
      case '\\':
        out += "\\\\";
        break;
      case '\n':
        out += "\\n";
        break;
      case '\t':
        out += "\\t";
        break;
      default:
        if (static_cast<unsigned char>(c) < 0x20) {
          out += fmt::format("\\u{:04x}", static_cast<int>(c));
        } else {
          out += c;
        }
    }
  }
  return out + "\"";
}

// JSON numbers: finite values only (NaN/inf are not JSON).
std::string num(double v) {
  return std::isfinite(v) ? fmt::format("{:.6g}", v) : std::string("null");
}

std::string json_distribution(const Distribution& d) {
  return fmt::format(R"({{"count": {}, "mean": {}, "p50": {}, "p95": {}, "p99": {}, "max": {}}})",
                     d.count, num(d.mean), num(d.p50), num(d.p95), num(d.p99), num(d.max));
}

std::string text_distribution(const char* name, const Distribution& d, const char* unit,
                              int decimals) {
  return fmt::format(
      "  {:<24} p50 {:>9.{}f}  p95 {:>9.{}f}  p99 {:>9.{}f}  max {:>9.{}f}  "
      "mean {:>9.{}f} {}\n",
      name, d.p50, decimals, d.p95, decimals, d.p99, decimals, d.max, decimals, d.mean, decimals,
      unit);
}

double share(const Distribution& stage, const Distribution& total) {
  return total.mean > 0.0 ? 100.0 * stage.mean / total.mean : 0.0;
}

}  // namespace

Distribution distribution(std::vector<float> values) {
  Distribution d;
  d.count = values.size();
  if (values.empty()) return d;
  std::sort(values.begin(), values.end());
  d.mean = std::accumulate(values.begin(), values.end(), 0.0) / static_cast<double>(values.size());
  d.p50 = rank(values, 0.50);
  d.p95 = rank(values, 0.95);
  d.p99 = rank(values, 0.99);
  d.max = values.back();
  return d;
}

std::string format_timing_text(const ReplaySummary& s) {
  std::string out;
  out += fmt::format("livod replay of {}\n", s.config_file);
  out += fmt::format(
      "frames: {} poses; scans in {}, before IMU init {}, out of order {}, queue overflow {}; "
      "frames without update {}; degenerate frames {}; scans not put into the map (no new "
      "viewpoint, lio.map_min_move_m) {}\n",
      s.frames, s.counters.scans_in, s.counters.scans_before_init, s.counters.scans_out_of_order,
      s.counters.scans_queue_overflow, s.counters.frames_without_update, s.degenerate_frames,
      s.counters.scans_not_mapped);
  out += fmt::format("imu: samples in {}, out of order {}, queue overflow {}; init: {}\n",
                     s.counters.imu_in, s.counters.imu_out_of_order, s.counters.imu_queue_overflow,
                     s.init_status);
  out += "\nper-frame estimator time (ms):\n";
  out += text_distribution("total (wall)", s.frame_ms, "ms", 3);
  out += text_distribution("total (CPU, all threads)", s.frame_cpu_ms, "ms", 3);
  out += text_distribution("propagate", s.propagate_ms, "ms", 3);
  out += text_distribution("undistort", s.undistort_ms, "ms", 3);
  out += text_distribution("downsample", s.downsample_ms, "ms", 3);
  out += text_distribution("residuals", s.residuals_ms, "ms", 3);
  out += text_distribution("update", s.update_ms, "ms", 3);
  out += text_distribution("map", s.map_ms, "ms", 3);
  out += fmt::format(
      "  time split (share of the mean frame): propagate {:.1f} %, undistort {:.1f} %, "
      "downsample {:.1f} %, residuals {:.1f} %, update {:.1f} %, map {:.1f} %\n",
      share(s.propagate_ms, s.frame_ms), share(s.undistort_ms, s.frame_ms),
      share(s.downsample_ms, s.frame_ms), share(s.residuals_ms, s.frame_ms),
      share(s.update_ms, s.frame_ms), share(s.map_ms, s.frame_ms));
  out += "\nper-frame counts:\n";
  out += text_distribution("raw points", s.raw_points, "", 0);
  out += text_distribution("points after downsample", s.used_points, "", 0);
  out += text_distribution("matched points", s.matched, "", 0);
  out += text_distribution("iterations", s.iterations, "", 1);
  out += fmt::format(
      "\nrun: recording {:.3f} s replayed in {:.3f} s wall (real-time factor {:.2f}x); decode "
      "{:.3f} "
      "s, estimator {:.3f} s, outputs {:.3f} s\n",
      s.recording_s, s.wall_s, s.realtime_factor, s.decode_s, s.estimator_s, s.output_s);
  out += fmt::format("memory: peak RSS {:.1f} MiB, final RSS {:.1f} MiB\n",
                     static_cast<double>(s.peak_rss_bytes) / kMiB,
                     static_cast<double>(s.final_rss_bytes) / kMiB);
  out += fmt::format(
      "map (estimator): {} root voxels, {} nodes, {} planes, {} stored points, {:.2f} MiB (peak "
      "{:.2f} MiB), {} voxels removed by sliding\n",
      s.map.root_voxels, s.map.nodes, s.map.planes, s.map.stored_points,
      static_cast<double>(s.map.bytes) / kMiB, static_cast<double>(s.map_bytes_peak) / kMiB,
      s.map.removed_voxels);
  out += fmt::format("map (map.pcd): {} points, {} dropped after the budget was spent\n",
                     s.exported_points, s.exported_dropped);
  if (s.vio_ms.count > 0) {
    const auto& c = s.counters;
    out += fmt::format(
        "\nvisual update: images in {}, image groups {}, visual updates {}, unused (before the "
        "first scan's end) {}, late {}, dropped {}, rejected {}; inverse exposure at the end "
        "{:.4f}\n",
        c.images_in, c.image_groups, c.vio_updates, c.images_unused, c.images_late,
        c.images_dropped, c.images_rejected, s.inv_exposure);
    out += text_distribution("per image (wall)", s.vio_ms, "ms", 3);
    out += text_distribution("pyramid", s.vio_pyramid_ms, "ms", 3);
    out += text_distribution("selection", s.vio_selection_ms, "ms", 3);
    out += text_distribution("update", s.vio_update_ms, "ms", 3);
    out += text_distribution("map", s.vio_map_ms, "ms", 3);
    out += text_distribution("patches used", s.vio_patches, "", 0);
    out += fmt::format(
        "visual map: {} points, {} reference patches, {:.2f} MiB; {} created, {} left the sliding "
        "box, {} evicted by the budget\n",
        s.visual_map.points, s.visual_map.observations,
        static_cast<double>(s.visual_map.bytes) / kMiB, s.visual_map.created,
        s.visual_map.removed_sliding, s.visual_map.removed_budget);
  }
  out += "\nsensors:\n";
  for (const auto& sensor : s.sensors) {
    const auto& c = sensor.clock;
    out += fmt::format("  {} ({}): {}\n    {}\n", sensor.name, sensor.role, sensor.file,
                       sensor.counters);
    out += fmt::format(
        "    scans {}, imu samples {}, images {}; clock {} ({}): offset {:.9f} s, skew {:+.3f} "
        "ppm, "
        "residual median {:.1f} us, jitter {:.1f} us, observations {}, resets {}, rejected {}; "
        "time_offset_s {:+.6f}\n",
        sensor.scans, sensor.imu_samples, sensor.images, c.mode, c.quality, c.offset_s, c.skew_ppm,
        c.residual_median_us, c.jitter_us, c.observations, c.resets, c.rejected, c.time_offset_s);
  }
  return out;
}

std::string format_timing_json(const ReplaySummary& s) {
  std::string out = "{\n";
  out += fmt::format("  \"config\": {},\n", json_string(s.config_file));
  out += fmt::format(
      "  \"frames\": {}, \"scans_in\": {}, \"scans_before_init\": {}, \"scans_out_of_order\": {}, "
      "\"frames_without_update\": {}, \"degenerate_frames\": {}, \"scans_not_mapped\": {},\n",
      s.frames, s.counters.scans_in, s.counters.scans_before_init, s.counters.scans_out_of_order,
      s.counters.frames_without_update, s.degenerate_frames, s.counters.scans_not_mapped);
  out += fmt::format("  \"imu_in\": {}, \"imu_out_of_order\": {}, \"init_status\": {},\n",
                     s.counters.imu_in, s.counters.imu_out_of_order, json_string(s.init_status));
  out += fmt::format("  \"frame_ms\": {},\n  \"frame_cpu_ms\": {},\n",
                     json_distribution(s.frame_ms), json_distribution(s.frame_cpu_ms));
  out += fmt::format(
      "  \"stage_ms\": {{\"propagate\": {}, \"undistort\": {}, \"downsample\": {}, \"residuals\": "
      "{}, "
      "\"update\": {}, "
      "\"map\": {}}},\n",
      json_distribution(s.propagate_ms), json_distribution(s.undistort_ms),
      json_distribution(s.downsample_ms), json_distribution(s.residuals_ms),
      json_distribution(s.update_ms), json_distribution(s.map_ms));
  out += fmt::format(
      "  \"raw_points\": {},\n  \"used_points\": {},\n  \"matched\": {},\n  \"iterations\": {},\n",
      json_distribution(s.raw_points), json_distribution(s.used_points),
      json_distribution(s.matched), json_distribution(s.iterations));
  out += fmt::format(
      "  \"recording_s\": {}, \"wall_s\": {}, \"decode_s\": {}, \"estimator_s\": {}, \"output_s\": "
      "{}, \"realtime_factor\": {},\n",
      num(s.recording_s), num(s.wall_s), num(s.decode_s), num(s.estimator_s), num(s.output_s),
      num(s.realtime_factor));
  out += fmt::format("  \"peak_rss_bytes\": {}, \"final_rss_bytes\": {},\n", s.peak_rss_bytes,
                     s.final_rss_bytes);
  out += fmt::format(
      "  \"map\": {{\"root_voxels\": {}, \"nodes\": {}, \"planes\": {}, \"stored_points\": {}, "
      "\"bytes\": {}, \"bytes_peak\": {}, \"removed_voxels\": {}}},\n",
      s.map.root_voxels, s.map.nodes, s.map.planes, s.map.stored_points, s.map.bytes,
      s.map_bytes_peak, s.map.removed_voxels);
  out += fmt::format("  \"exported_points\": {}, \"exported_dropped\": {},\n", s.exported_points,
                     s.exported_dropped);
  out += fmt::format(
      "  \"vio\": {{\"images_in\": {}, \"image_groups\": {}, \"updates\": {}, \"unused\": {}, "
      "\"late\": {}, "
      "\"dropped\": {}, \"rejected\": {}, \"inv_exposure\": {}, \"ms\": {}, \"pyramid_ms\": {}, "
      "\"selection_ms\": {}, \"update_ms\": {}, \"map_ms\": {}, \"patches\": {}, "
      "\"visual_map\": {{\"points\": {}, \"observations\": {}, \"bytes\": {}, \"created\": {}, "
      "\"removed_sliding\": {}, \"removed_budget\": {}}}}},\n",
      s.counters.images_in, s.counters.image_groups, s.counters.vio_updates,
      s.counters.images_unused, s.counters.images_late, s.counters.images_dropped,
      s.counters.images_rejected, num(s.inv_exposure), json_distribution(s.vio_ms),
      json_distribution(s.vio_pyramid_ms), json_distribution(s.vio_selection_ms),
      json_distribution(s.vio_update_ms), json_distribution(s.vio_map_ms),
      json_distribution(s.vio_patches), s.visual_map.points, s.visual_map.observations,
      s.visual_map.bytes, s.visual_map.created, s.visual_map.removed_sliding,
      s.visual_map.removed_budget);
  out += "  \"sensors\": [";
  for (std::size_t i = 0; i < s.sensors.size(); ++i) {
    const auto& sensor = s.sensors[i];
    const auto& c = sensor.clock;
    out += fmt::format(
        "{}\n    {{\"name\": {}, \"role\": {}, \"file\": {}, \"counters\": {}, \"scans\": {}, "
        "\"imu_samples\": {}, \"images\": {}, \"clock\": {{\"mode\": {}, \"quality\": {}, "
        "\"offset_s\": {:.9f}, "
        "\"skew_ppm\": {}, \"residual_median_us\": {}, \"jitter_us\": {}, \"observations\": {}, "
        "\"resets\": {}, \"rejected\": {}, \"time_offset_s\": {}}}}}",
        i == 0 ? "" : ",", json_string(sensor.name), json_string(sensor.role),
        json_string(sensor.file), json_string(sensor.counters), sensor.scans, sensor.imu_samples,
        sensor.images, json_string(c.mode), json_string(c.quality), c.offset_s, num(c.skew_ppm),
        num(c.residual_median_us), num(c.jitter_us), c.observations, c.resets, c.rejected,
        num(c.time_offset_s));
  }
  out += "\n  ]\n}\n";
  return out;
}

std::size_t peak_rss_bytes() {
  rusage usage{};
  if (getrusage(RUSAGE_SELF, &usage) != 0) return 0;
  return static_cast<std::size_t>(usage.ru_maxrss) * 1024;  // Linux reports KiB
}

std::size_t current_rss_bytes() {
  std::FILE* f = std::fopen("/proc/self/statm", "r");
  if (f == nullptr) return 0;
  unsigned long size_pages = 0;
  unsigned long resident_pages = 0;
  const int n = std::fscanf(f, "%lu %lu", &size_pages, &resident_pages);
  std::fclose(f);
  if (n != 2) return 0;
  return static_cast<std::size_t>(resident_pages) * static_cast<std::size_t>(sysconf(_SC_PAGESIZE));
}

FrameTable::FrameTable(const std::filesystem::path& path) : file_(path) {
  file_.stream()
      << "frame,t,raw_points,used_points,matched,iterations,converged,updated,degenerate,"
         "translation_ratio,propagate_ms,undistort_ms,downsample_ms,residuals_ms,update_ms,map_ms,"
         "total_ms,"
         "cpu_ms,map_planes,map_bytes,exported_points,rss_bytes,image,vio_ms,vio_patches,"
         "inv_exposure\n";
}

void FrameTable::add(std::size_t frame, const estimator::FrameReport& r, double cpu_ms,
                     std::size_t exported_points, std::size_t rss_bytes) {
  const auto& t = r.timings;
  file_.stream() << fmt::format(
      "{},{},{},{},{},{},{},{},{},{:.6g},{:.4f},{:.4f},{:.4f},{:.4f},{:.4f},{:.4f},{:.4f},{:.4f},{}"
      ","
      "{},{},{},",
      frame, format_seconds(r.t.ns), r.raw_points, r.used_points, r.matched, r.iterations,
      r.converged ? 1 : 0, r.updated ? 1 : 0, r.degeneracy.degenerate ? 1 : 0,
      r.degeneracy.translation_ratio, t.propagate_ms, t.undistort_ms, t.downsample_ms,
      t.residuals_ms, t.update_ms, t.map_ms, t.total_ms, cpu_ms, r.map.planes, r.map.bytes,
      exported_points, rss_bytes);
  const bool image = r.kind == estimator::MeasurementGroup::Kind::image;
  file_.stream() << fmt::format("{},{:.4f},{},{:.6g}\n", image ? 1 : 0, r.timings.vio_ms,
                                r.vio.patches, image ? r.vio.inv_exposure : 0.0);
}

void FrameTable::close() {
  file_.commit();
}

}  // namespace livod::daemon::replay
