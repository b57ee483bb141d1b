#!/usr/bin/env bash
# Sets everything up on a fresh Debian 12 machine and runs livod's main job on a default input:
# installs packages, builds the release preset, simulates a handheld Livox Mid-360 sequence in
# the sensor's real wire format (no sensors needed), runs the LiDAR-inertial odometry on it with
# `livod replay` and scores the trajectory against the simulator's ground truth.
set -euo pipefail
cd "$(dirname "$0")/.."
./scripts/install-deps.sh
cmake --preset release >/dev/null
cmake --build --preset release -j "$(nproc)" --target livod
livod=./build/release/daemon/livod
out=${LIVOD_DEMO_DIR:-out/demo}
rm -rf "$out"
"$livod" sim --scenario room_handheld_mid360 --duration 20 -o "$out/sim"
"$livod" inspect "$out/sim/mid360.pcap"
"$livod" replay --config "$out/sim/config.yaml" -o "$out/replay"
"$livod" eval "$out/replay/trajectory.txt" "$out/sim/groundtruth.txt"
echo "trajectory, map and timing report: $out/replay/"
