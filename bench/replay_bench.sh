#!/usr/bin/env bash
# End-to-end replay benchmarks (results in docs/replay.md): simulate a scenario with `livod sim`,
# replay it with `livod replay`, print the timing report's figures.
#
#   bench/replay_bench.sh timing [BUILD_DIR]   per-frame time of each rig (one- and two-LiDAR),
#                                              36-40 s each, REPEAT (default 5) replays per rig
#   bench/replay_bench.sh memory [BUILD_DIR]   15 min of the Mid-360 room: RSS and map bytes over
#                                              time (needs ~3 GB in $TMPDIR for the capture)
#
# BUILD_DIR defaults to build/release (a Release build: -O2, portable, IEEE-exact).
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

repeat=${REPEAT:-5}

# $1 scenario, $2 seconds, $3 estimator settings (YAML flow mapping, may be empty). The replay runs
# $repeat times: the machine is shared, so the report gives the median over runs of each figure
# (per-run p50/p95/p99 of the per-frame wall time), then the time split of the median run.
run() {
  local scenario=$1 duration=$2 estimator=$3
  local sim="$work/$scenario" out="$work/$scenario-replay"
  "$livod" sim --scenario "$scenario" --duration "$duration" --no-images -o "$sim" > /dev/null
  cp "$sim/config.yaml" "$sim/replay.yaml"
  if [ -n "$estimator" ]; then echo "estimator: $estimator" >> "$sim/replay.yaml"; fi
  local runs="$work/$scenario-runs.txt"
  : > "$runs"
  for i in $(seq "$repeat"); do
    "$livod" replay --config "$sim/replay.yaml" -o "$out-$i" -q > /dev/null
    # p50 p95 p99 of the per-frame wall time, then the run folder
    awk '/^  total \(wall\)/ {print $4, $6, $8}' "$out-$i/timing.txt" | tr '\n' ' ' >> "$runs"
    echo "$out-$i" >> "$runs"
  done
  local median_run
  median_run=$(sort -n "$runs" | awk -v n="$repeat" 'NR == int((n + 1) / 2) {print $4}')
  local ate
  ate=$("$livod" eval "$median_run/trajectory.txt" "$sim/groundtruth.txt" | awk '/^ATE/ {print $3}')
  echo "== $scenario ($duration s) estimator: ${estimator:-defaults}; ATE RMSE $ate m"
  for col in 1 2 3; do
    sort -n -k"$col" "$runs" | awk -v c="$col" -v n="$repeat" \
      'NR == int((n + 1) / 2) {printf "median over %d runs of the per-frame %s: %.2f ms\n", n, (c == 1 ? "p50" : c == 2 ? "p95" : "p99"), $c}'
  done
  sed -n '/per-frame estimator time/,/^memory/p' "$median_run/timing.txt"
  grep '^map' "$median_run/timing.txt"
  echo "$median_run" > "$work/last"
}

case "$mode" in
  timing)
    # The issue's benchmark: OS1-64 on the street, with FAST_LIO's OS1-64 downsampling (every 4th
    # point, 0.5 m cells) and a denser one (every 2nd point, 0.2 m cells).
    run street_drone_os1_64 40 "{lio: {point_filter_num: 4, filter_size_surf: 0.5}}"
    run street_drone_os1_64 40 "{lio: {point_filter_num: 2, filter_size_surf: 0.2}}"
    run room_handheld_os1_64 40 "{lio: {point_filter_num: 2, filter_size_surf: 0.2}}"
    run street_vehicle_os1_128 36 "{lio: {point_filter_num: 4, filter_size_surf: 0.5}}"
    run street_vehicle_vlp16 36 "{lio: {beam_err_deg: 0.1, filter_size_surf: 0.2}}"
    run room_handheld_mid360 40 ""
    run room_handheld_avia 40 ""
    # Several LiDARs (docs/estimator.md "Several LiDARs"): every scan end of either LiDAR is a
    # frame, so frames come at twice the rate with about half the points each.
    run room_dual_mid360 40 ""
    run street_vehicle_vlp16_avia 36 "{lio: {beam_err_deg: 0.1, filter_size_surf: 0.2}}"
    ;;
  memory)
    repeat=1
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
