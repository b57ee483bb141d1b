#!/usr/bin/env bash
# End-to-end replay benchmarks (results in docs/replay.md): simulate a scenario with `livod sim`,
# replay it with `livod replay`, print the timing report's figures.
#
#   bench/replay_bench.sh timing [BUILD_DIR]   per-frame time of each rig, 40 s each
#   bench/replay_bench.sh memory [BUILD_DIR]   15 min of the Mid-360 room: RSS and map bytes over
#                                              time (needs ~3 GB in $TMPDIR for the capture)
#
# BUILD_DIR defaults to build/release (a Release build: -O2, no -ffast-math, no -march=native).
# Per-frame figures are wall time and CPU time over all threads (unaffected by other processes); run on an
# otherwise idle machine for wall figures that mean something.
set -euo pipefail
cd "$(dirname "$0")/.."
mode=${1:-timing}
build=${2:-build/release}
livod="$build/daemon/livod"
[ -x "$livod" ] || { echo "no $livod: build the livod target first" >&2; exit 1; }
work=$(mktemp -d "${TMPDIR:-/tmp}/livod-replay-bench.XXXXXX")
trap 'rm -rf "$work"' EXIT

# $1 scenario, $2 seconds, $3 estimator settings (YAML flow mapping, may be empty)
run() {
  local scenario=$1 duration=$2 estimator=$3
  local sim="$work/$scenario" out="$work/$scenario-replay"
  "$livod" sim --scenario "$scenario" --duration "$duration" --no-images -o "$sim" > /dev/null
  cp "$sim/config.yaml" "$sim/replay.yaml"
  if [ -n "$estimator" ]; then echo "estimator: $estimator" >> "$sim/replay.yaml"; fi
  "$livod" replay --config "$sim/replay.yaml" -o "$out" -q > /dev/null
  local ate
  ate=$("$livod" eval "$out/trajectory.txt" "$sim/groundtruth.txt" | awk '/^ATE/ {print $3}')
  echo "== $scenario ($duration s) estimator: ${estimator:-defaults}; ATE RMSE $ate m"
  sed -n '/per-frame estimator time/,/^memory/p' "$out/timing.txt"
  grep '^map' "$out/timing.txt"
  echo "$out" > "$work/last"
}

case "$mode" in
  timing)
    run street_drone_os1_64 40 "{lio: {point_filter_num: 2, filter_size_surf: 0.2}}"
    run room_handheld_os1_64 40 "{lio: {point_filter_num: 2, filter_size_surf: 0.2}}"
    run street_vehicle_os1_128 36 "{lio: {point_filter_num: 4, filter_size_surf: 0.5}}"
    run street_vehicle_vlp16 36 "{lio: {beam_err_deg: 0.1, filter_size_surf: 0.2}}"
    run room_handheld_mid360 40 ""
    run room_handheld_avia 40 ""
    ;;
  memory)
    run room_handheld_mid360 900 ""
    out=$(cat "$work/last")
    # frames.csv columns: t (2), map_bytes (20), exported_points (21), rss_bytes (22).
    awk -F, 'NR == 2 {t0 = $2}
             NR > 1 {m = int(($2 - t0) / 60); if (!(m in seen)) {seen[m] = 1;
               printf "minute %3d: RSS %7.1f MiB, estimator map %6.2f MiB, map.pcd points %d\n",
                      m, $22 / 1048576, $20 / 1048576, $21}}' "$out/frames.csv" |
      awk 'NR == 1 || NR == 2 || NR % 5 == 1'
    ;;
  *)
    echo "usage: $0 timing|memory [BUILD_DIR]" >&2
    exit 2
    ;;
esac
