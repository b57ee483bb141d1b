#!/usr/bin/env bash
# Benchmarks of the daemon (`livod run`, results in docs/daemon.md): a simulated capture is sent
# over loopback UDP to the daemon's sensor ports by bench/pcap_udp_sender (a sensor stand-in), the
# daemon runs as on a robot and publishes over LCM, then stops on SIGTERM and reports. Everything
# runs inside a private network namespace (scripts/netns-run.sh): the LCM multicast and the
# sensor traffic stay on its loopback.
#
#   bench/daemon_bench.sh latency [BUILD_DIR]   OS1-64 street (40 s) at the recorded pace: pose and
#                                               IMU-rate pose latency p50/p99, frame time, losses
#   bench/daemon_bench.sh rate [BUILD_DIR]      OS1-128 street sent at twice its line rate for 60 s
#                                               (a 30 s capture at speed 2, four times): packet losses
#   bench/daemon_bench.sh memory [BUILD_DIR]    Mid-360 room for MINUTES (default 30) at the recorded
#                                               pace: the daemon's RSS every minute (needs ~200 MB
#                                               of $TMPDIR per minute for the capture)
#
# BUILD_DIR defaults to build/release and needs the targets livod and pcap_udp_sender. The daemon
# runs with the shipped service configuration's SCHED_FIFO priorities (capture 50, scheduler 40;
# needs root or RLIMIT_RTPRIO, else the refusal is logged); REALTIME=0 runs it without.
# CPU_LATENCY_US=N adds realtime.cpu_dma_latency_us: N (a PM QoS wake-up latency bound; needs write
# access to /dev/cpu_dma_latency; docs/daemon.md "Real-time settings").
set -euo pipefail
cd "$(dirname "$0")/.."
mode=${1:-latency}
build=${2:-build/release}
if [[ ${LIVOD_NETNS:-} != 1 ]]; then
  exec bash scripts/netns-run.sh bash "$0" "$mode" "$build"
fi
livod="$build/daemon/livod"
sender="$build/bench/pcap_udp_sender"
for f in "$livod" "$sender"; do
  [ -x "$f" ] || { echo "no $f: build the livod and pcap_udp_sender targets first" >&2; exit 1; }
done
work=$(mktemp -d "${TMPDIR:-/tmp}/livod-daemon-bench.XXXXXX")
trap 'rm -rf "$work"' EXIT

# $1 scenario, $2 seconds, $3 estimator settings (YAML flow mapping, may be empty): simulates the
# scenario and writes $work/$1/live.yaml, its LiDAR turned into a live UDP source on loopback.
prepare() {
  local scenario=$1 duration=$2 estimator=$3 sim="$work/$1"
  "$livod" sim --scenario "$scenario" --duration "$duration" --no-images -o "$sim" > /dev/null
  local ports
  case $(grep -m1 'driver:' "$sim/config.yaml" | awk '{print $2}') in
    ouster) ports="{lidar: 7502, imu: 7503}" ;;
    livox_sdk2) ports="{lidar: 56301, imu: 56401}" ;;
    *) echo "prepare: $scenario: no live ports for its driver" >&2; exit 1 ;;
  esac
  sed -e "s|      replay: {file: \(.*\)\.pcap}|      udp: {bind_address: 127.0.0.1, ports: $ports, socket_buffer_bytes: 16777216}|" \
      -e '/^outputs:/,$d' "$sim/config.yaml" > "$sim/live.yaml"
  cat >> "$sim/live.yaml" <<EOF
outputs:
  lcm: {url: "udpm://239.255.76.67:7667?ttl=0", publish_imu_rate: true}
  timing_report: $sim/timing.txt
health: {period_s: 1.0}
EOF
  # The shipped service configuration's real-time settings (systemd/livod.example.yaml), as on a
  # robot; REALTIME=0 measures normal scheduling.
  if [ "${REALTIME:-1}" != 0 ]; then
    echo "realtime: {capture_priority: 50, scheduler_priority: 40, cpu_dma_latency_us: ${CPU_LATENCY_US:--1}}" >> "$sim/live.yaml"
  fi
  if [ -n "$estimator" ]; then echo "estimator: $estimator" >> "$sim/live.yaml"; fi
}

# Starts `livod run` on $1 (a live.yaml), logging to $1.log; waits until it is ready.
start_daemon() {
  "$livod" run --config "$1" > "$1.log" 2>&1 &
  daemon_pid=$!
  for _ in $(seq 300); do
    grep -q 'ready' "$1.log" && return 0
    sleep 0.1
  done
  echo "livod run did not get ready:" >&2
  cat "$1.log" >&2
  exit 1
}

stop_daemon() {
  sleep 1
  kill -TERM "$daemon_pid"
  wait "$daemon_pid"
}

case "$mode" in
  latency)
    # FAST_LIO's OS1-64 downsampling, as the replay benchmark's first figure.
    prepare street_drone_os1_64 40 "{lio: {point_filter_num: 4, filter_size_surf: 0.5}}"
    sim="$work/street_drone_os1_64"
    start_daemon "$sim/live.yaml"
    "$sender" "$sim/os1.pcap"
    stop_daemon
    grep -E 'udp: kernel drops|stopped by' "$sim/live.yaml.log"
    cat "$sim/timing.txt"
    ;;
  rate)
    # Twice an OS1-128's 10 Hz packet rate (1280 datagrams/s, ~32 MB/s): the capture path must lose
    # nothing. The estimator sees scans twice as often as their time stamps say and may drop some;
    # that is not what is measured here.
    prepare street_vehicle_os1_128 30 "{lio: {point_filter_num: 4, filter_size_surf: 0.5}}"
    sim="$work/street_vehicle_os1_128"
    start_daemon "$sim/live.yaml"
    "$sender" "$sim/os1.pcap" --speed 2 --repeat 4
    stop_daemon
    grep -E 'udp: kernel drops|stopped by' "$sim/live.yaml.log"
    ;;
  memory)
    minutes=${MINUTES:-30}
    prepare room_handheld_mid360 $((minutes * 60 + 10)) ""
    sim="$work/room_handheld_mid360"
    start_daemon "$sim/live.yaml"
    "$sender" "$sim/mid360.pcap" > "$sim/sender.txt" &
    sender_pid=$!
    echo "minute RSS(MiB)"
    m=0
    while kill -0 "$sender_pid" 2> /dev/null; do
      awk -v m="$m" '/^VmRSS/ {printf "%d %.1f\n", m, $2 / 1024}' "/proc/$daemon_pid/status"
      sleep 60
      m=$((m + 1))
    done
    cat "$sim/sender.txt"
    stop_daemon
    grep -E 'udp: kernel drops|stopped by' "$sim/live.yaml.log"
    ;;
  *)
    echo "usage: $0 latency|rate|memory [BUILD_DIR]" >&2
    exit 2
    ;;
esac
