#!/usr/bin/env bash
# Installs every Debian 12 package livod needs to build, test, fuzz and benchmark.
# Idempotent: when everything is present it only runs dpkg-query and exits (about a second).
set -euo pipefail

packages=(
  # toolchain
  build-essential cmake ninja-build pkg-config git clang clang-format libclang-rt-14-dev
  # maths, geometry, images
  libeigen3-dev libpcl-dev libopencv-dev
  # sensors and transports
  libv4l-dev libusb-1.0-0-dev libaravis-dev aravis-tools libpcap-dev can-utils iproute2
  # logging, config, CLI, JSON
  libspdlog-dev libfmt-dev libyaml-cpp-dev libcli11-dev nlohmann-json3-dev
  # XML (Velodyne/VeloView calibration files)
  libexpat1-dev
  # LCM (C++ and the Java pieces lcm-spy needs)
  liblcm-dev liblcm-bin liblcm-java libjchart2d-java libglib2.0-dev default-jdk-headless
  # systemd integration (systemd: systemd-analyze and systemd-sysusers check the unit in tests)
  libsystemd-dev systemd
  # bag chunk compression, hashing in tests
  libbz2-dev liblz4-dev libssl-dev zlib1g-dev
  # tests and benchmarks (python3: the generated LCM Python types are tested with it)
  libgtest-dev libgmock-dev libbenchmark-dev libreaderwriterqueue-dev python3
)

missing=()
for p in "${packages[@]}"; do
  if ! dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed"; then
    missing+=("$p")
  fi
done

if ((${#missing[@]} == 0)); then
  echo "install-deps: all ${#packages[@]} packages present"
  exit 0
fi

echo "install-deps: installing ${#missing[@]} packages: ${missing[*]}"
SUDO=""
if [[ $(id -u) -ne 0 ]]; then SUDO="sudo"; fi
export DEBIAN_FRONTEND=noninteractive
$SUDO apt-get update -qq
$SUDO apt-get install -y -qq --no-install-recommends "${missing[@]}" >/dev/null
echo "install-deps: done"
