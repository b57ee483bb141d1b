#!/usr/bin/env bash
# Map save without stalling the loop (docs/deploy.md "Saving the map"): the scheduler's frame time
# p99 while the daemon saves a 2 M-point map every few seconds, against the same run without
# saves. `livod replay --realtime` runs a simulated OS1-128 street capture at its recorded pace
# through the daemon's threads (the scheduler, the publisher, the map writer); the map's voxel cell
# is small (--map-cell 0.02) so that the map reaches its 2 M-point budget within seconds, and saves
# (SIGUSR1, overwrite mode so the disk does not fill) start once it has. The runs alternate
# (none, save, none, save...) so that both see the same machine load; the frame time is the
# estimator's per-scan wall time from OUTDIR/timing.txt (0.02 ms bins up to 20 ms, then 1 ms).
#
#   bench/map_save_bench.sh [BUILD_DIR] [PAIRS] [SAVE_PERIOD_S]
#   SIM_DIR=FOLDER bench/map_save_bench.sh ...   reuse a simulated street_vehicle_os1_128 folder
#
# BUILD_DIR defaults to build/release (target livod), PAIRS to 3, SAVE_PERIOD_S to 2. Run it with
# the normal priority (not under `nice`: a niced daemon measures the other tenants of the machine)
# and report the spread over the pairs. Prints one line per run and a summary.
set -euo pipefail
cd "$(dirname "$0")/.."
build=${1:-build/release}
pairs=${2:-3}
period=${3:-2}
livod="$build/daemon/livod"
[ -x "$livod" ] || { echo "no $livod: build the livod target first" >&2; exit 1; }
work=$(mktemp -d "${TMPDIR:-/tmp}/livod-map-save-bench.XXXXXX")
trap 'rm -rf "$work"' EXIT

duration=${DURATION_S:-40}  # simulated
run_s=${RUN_S:-30}           # replayed per run
if [ -n "${SIM_DIR:-}" ]; then
  # A folder an earlier `livod sim --scenario street_vehicle_os1_128` wrote (it takes minutes).
  mkdir -p "$work/sim" && cp "$SIM_DIR/config.yaml" "$SIM_DIR/os1.json" "$work/sim/"
  ln -s "$(realpath "$SIM_DIR/os1.pcap")" "$work/sim/os1.pcap"
else
  nice -n 19 "$livod" sim --scenario street_vehicle_os1_128 --duration "$duration" --no-images \
    -o "$work/sim" > /dev/null
fi
# The daemon's own outputs only (no LCM: no subscriber), saves replacing one file.
sed -e '/^outputs:/,$d' "$work/sim/config.yaml" > "$work/sim/bench.yaml"
cat >> "$work/sim/bench.yaml" <<YAML
outputs:
  lcm: null
  map_saves: {overwrite: true}
estimator: {lio: {point_filter_num: 2, filter_size_surf: 0.2}}
YAML

# $1 run name, $2 "save" or "none". Prints: name p50 p99 max frames saves(2M) save_s(mean).
run() {
  local out="$work/$1"
  mkdir -p "$out"
  "$livod" replay --realtime --config "$work/sim/bench.yaml" -o "$out" --map-cell 0.02 \
    --map-max-points 2000000 --max-duration "$run_s" "$work/sim/os1.pcap" > "$out/log.txt" 2>&1 &
  local pid=$!
  if [ "$2" = save ]; then
    # Saves from 5 s in (the filter runs), every $period s until the end; the map reaches its
    # 2 M points after about 15 s on the 2-core machine (the log counts the full-size saves).
    sleep 5
    while kill -0 "$pid" 2> /dev/null; do
      kill -USR1 "$pid" 2> /dev/null || true
      sleep "$period"
    done
  fi
  wait "$pid" || true
  local line
  line=$(grep 'frame time (wall)' "$out/timing.txt") || { echo "$1: no timing report" >&2; cat "$out/log.txt" >&2; return 1; }
  local saves full
  saves=$(grep -c 'map saved:' "$out/log.txt" || true)
  full=$(grep -c 'map saved: .*(2000000 points' "$out/log.txt" || true)
  local save_s
  save_s=$({ grep -o 'MB, [0-9.]* s;' "$out/log.txt" || true; } | awk '{s += $2; n++} END {if (n) printf "%.3f", s / n; else print "-"}')
  echo "$1 $(echo "$line" | awk '{for (i = 1; i <= NF; i++) {if ($i == "count") c = $(i + 1); if ($i == "p50") a = $(i + 1); if ($i == "p99") b = $(i + 1); if ($i == "max") m = $(i + 1)}} END {printf "frames %s p50 %s p99 %s max %s", c, a, b, m}') saves $saves (2M-point: $full) mean write ${save_s} s"
}

echo "OS1-128 street, ${run_s} s per run, replay --realtime, map cell 0.02 m, budget 2 M points, SIGUSR1 every ${period} s"
for i in $(seq "$pairs"); do
  run "none-$i" none
  run "save-$i" save
done | tee "$work/results.txt"
awk '
  { for (i = 1; i <= NF; i++) if ($i == "p99") p99 = $(i + 1)
    split($1, k, "-"); v[k[1]] = v[k[1]] " " p99; s[k[1]] += p99; n[k[1]]++ }
  END {
    for (m in s) printf "%s: p99 mean %.2f ms over %d runs (each:%s)\n", m, s[m] / n[m], n[m], v[m]
    if (n["none"] && n["save"]) printf "save / none p99: %+.1f %%\n", 100 * (s["save"] / n["save"] / (s["none"] / n["none"]) - 1)
  }' "$work/results.txt"
