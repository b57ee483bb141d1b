#!/usr/bin/env bash
# End-to-end replay benchmarks (results in docs/replay.md): simulate a scenario with `livod sim`,
# replay it with `livod replay`, print the timing report's figures.
#
#   bench/replay_bench.sh timing [BUILD_DIR]   per-frame time of each rig (one- and two-LiDAR),
#                                              36-40 s each, REPEAT (default 5) replays per rig
#   bench/replay_bench.sh memory [BUILD_DIR]   15 min of the Mid-360 room: RSS and map bytes over
#                                              time (needs ~3 GB in $TMPDIR for the capture)
#   bench/replay_bench.sh defaults [BUILD_DIR]  every simulated model with the configuration
#                                              `livod sim` writes (no estimator section) at each
#                                              rate of RATES (default '10 20' Hz), SEEDS (default
#                                              3) seeds each: per-frame p50 and p99 (wall and CPU)
#                                              and ATE. BEFORE=/path/to/livod replays the same
#                                              captures with another build too; MODELS='VLP-16
#                                              XT32' runs only those rows.
#   bench/replay_bench.sh sweep BUILD_DIR SCENARIO SECONDS RATE 'SETTINGS'...
#                                              one row per estimator setting (YAML flow mapping,
#                                              '' = defaults) over SEEDS seeds: mean ATE (and
#                                              per seed), p99;
#                                              SCENARIO is a name or a scenario file
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

# Figures of one replay folder: points p50, wall p50, wall p99, CPU p99.
figures() {
  awk '/^  total \(wall\)/ {w50 = $4; w99 = $8} /^  total \(CPU/ {c99 = $10}
       /^  points after downsample/ {p = $5} END {print p, w50, w99, c99}' "$1/timing.txt"
}

# mean, min and max of a column of numbers
stats() {
  awk '{s += $1; if (NR == 1 || $1 < lo) lo = $1; if (NR == 1 || $1 > hi) hi = $1}
       END {if (NR) printf "%.4f %.4f %.4f", s / NR, lo, hi}'
}

# $1 livod binary, $2 sim folder, $3 settings ('' = none), $4 output folder: prints
# "points wall-p50 wall-p99 cpu-p99 ate"
replay_one() {
  local bin=$1 sim=$2 settings=$3 out=$4
  # Beside config.yaml: its capture paths are relative to the file.
  local yaml
  yaml="$sim/$(basename "$out").yaml"
  cp "$sim/config.yaml" "$yaml"
  if [ -n "$settings" ]; then echo "estimator: $settings" >> "$yaml"; fi
  "$bin" replay --config "$yaml" -o "$out" -q > /dev/null
  local ate
  ate=$("$livod" eval "$out/trajectory.txt" "$sim/groundtruth.txt" | awk '/^ATE/ {print $3}')
  echo "$(figures "$out") $ate"
}

# The `livod sim` option that names scenario $1: a built-in scenario's name, or a scenario file's
# path (bench/scenarios/).
scenario_flag() {
  if [ -f "$1" ]; then echo --scenario-file; else echo --scenario; fi
}

# median over the rows of $work/rows of column $1 ($2 rows)
median_of() {
  sort -n -k"$1" "$work/rows" | awk -v c="$1" -v n="$2" 'NR == int((n + 1) / 2) {print $c}'
}

case "$mode" in
  defaults)
    seeds=${SEEDS:-3}
    printf "%-8s %-24s %4s %8s %8s %8s %8s %10s  %s\n" model scenario Hz points p50 p99 \
      "p99-CPU" "ATE-mean" "(min-max, m)"
    while read -r model scenario seconds; do
      # MODELS='VLP-16 XT32' runs only those rows.
      if [ -n "${MODELS:-}" ] && [[ " $MODELS " != *" $model "* ]]; then continue; fi
      for rate in ${RATES:-10 20}; do
        for build in after before; do
          bin=$livod
          if [ "$build" = before ]; then
            [ -n "${BEFORE:-}" ] || continue
            bin=$BEFORE
          fi
          : > "$work/rows"
          for seed in $(seq "$seeds"); do
            sim="$work/$(basename "$scenario" .yaml)-$rate-$seed"
            [ -d "$sim" ] || "$livod" sim "$(scenario_flag "$scenario")" "$scenario" --duration "$seconds" \
              --seed "$seed" --scan-rate "$rate" --no-images -o "$sim" > /dev/null
            replay_one "$bin" "$sim" "" "$sim-$build" >> "$work/rows"
            rm -rf "$sim-$build"
          done
          read -r ate lo hi <<< "$(awk '{print $5}' "$work/rows" | stats)"
          printf "%-8s %-24s %4s %8s %8s %8s %8s %10s  (%s-%s) %s\n" "$model" "$scenario" \
            "$rate" "$(median_of 1 "$seeds")" "$(median_of 2 "$seeds")" \
            "$(median_of 3 "$seeds")" "$(median_of 4 "$seeds")" "$ate" "$lo" "$hi" \
            "$([ "$build" = before ] && echo "[before]")"
        done
        rm -rf "$work/$(basename "$scenario" .yaml)-$rate-"*
      done
    done <<'EOF'
AVIA     room_handheld_avia      30
MID-360  room_handheld_mid360    30
OS1-64   room_handheld_os1_64    30
OS1-64   street_drone_os1_64     36
OS1-128  street_vehicle_os1_128  36
VLP-16   street_vehicle_vlp16    36
HDL-32E  street_vehicle_hdl32e   36
XT32     bench/scenarios/street_vehicle_xt32.yaml 36
EOF
    ;;
  sweep)
    scenario=$3 seconds=$4 rate=$5
    shift 5
    seeds=${SEEDS:-3}
    for seed in $(seq "$seeds"); do
      "$livod" sim "$(scenario_flag "$scenario")" "$scenario" --duration "$seconds" --seed "$seed" --scan-rate "$rate" \
        --no-images -o "$work/sim-$seed" > /dev/null
    done
    for settings in "$@"; do
      : > "$work/rows"
      for seed in $(seq "$seeds"); do
        replay_one "$livod" "$work/sim-$seed" "$settings" "$work/out-$seed" >> "$work/rows"
        rm -rf "$work/out-$seed"
      done
      read -r ate _ _ <<< "$(awk '{print $5}' "$work/rows" | stats)"
      p99=$(awk '{print $3}' "$work/rows" | sort -n | tail -1)
      cpu=$(awk '{print $4}' "$work/rows" | sort -n | tail -1)
      pts=$(awk '{print $1}' "$work/rows" | sort -n | tail -1)
      per_seed=$(awk '{printf "%s%.1f", (NR > 1 ? " / " : ""), 1000 * $5}' "$work/rows")
      printf "%s %s Hz  ATE %s (%s mm) m  p99 max %s ms (CPU %s)  points %s  %s\n" "$scenario" \
        "$rate" "$ate" "$per_seed" "$p99" "$cpu" "$pts" "${settings:-defaults}"
    done
    ;;

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
    echo "usage: $0 timing|memory|defaults [BUILD_DIR] | sweep BUILD_DIR SCENARIO SECONDS RATE SETTINGS..." >&2
    exit 2
    ;;
esac
