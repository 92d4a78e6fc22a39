#!/usr/bin/env bash
# Installs the Debian packages the project builds with (when run as root), or prints the exact
# apt-get line to run. Sourced by demo.sh and test.sh; safe to run again.
set -euo pipefail

MPPI_DEBIAN_PACKAGES=(
  build-essential cmake pkg-config git
  libeigen3-dev libtbb-dev libzip-dev libyaml-cpp-dev libopencv-dev librandom123-dev
  nlohmann-json3-dev catch2 libbenchmark-dev libcli11-dev
  python3 python3-numpy python3-dev python3-pytest pybind11-dev
  python3-distributed python3-optuna python3-pandas python3-sqlalchemy
  mesa-vulkan-drivers libvulkan-dev glslang-tools spirv-tools
  libplplot-dev plplot-driver-cairo fonts-dejavu-core libcmark-gfm-dev libcmark-gfm-extensions-dev
  libcpp-httplib-dev libssl-dev nodejs npm chromium
  coinor-libipopt-dev
  # ROS 1 (Debian's packages) for the nodes in ros/ (docs/ROS.md); the build goes on without them.
  ros-core-dev catkin ros-message-generation ros-std-msgs ros-geometry-msgs ros-nav-msgs
  python3-rospy python3-rosbag librosbag-dev
  python3-genpy python3-nav-msgs python3-geometry-msgs
)

mppi_missing_packages() {
  local missing=()
  for p in "${MPPI_DEBIAN_PACKAGES[@]}"; do
    # Machines that ship their own Node.js (not Debian's) conflict with Debian's npm; any working
    # node and npm on PATH serve the vendored web assets equally.
    if { [ "$p" = nodejs ] || [ "$p" = npm ]; } && command -v node >/dev/null && command -v npm >/dev/null; then
      continue
    fi
    dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed" || missing+=("$p")
  done
  echo "${missing[@]:-}"
}

mppi_setup() {
  local missing
  missing=$(mppi_missing_packages)
  if [ -z "$missing" ]; then
    return 0
  fi
  if [ "$(id -u)" -eq 0 ]; then
    echo "[setup] installing Debian packages: $missing"
    export DEBIAN_FRONTEND=noninteractive
    apt-get update -qq
    # shellcheck disable=SC2086
    apt-get install -y -qq --no-install-recommends $missing
  else
    echo "[setup] missing Debian packages. Run this, then try again:" >&2
    echo "  sudo apt-get install -y --no-install-recommends $missing" >&2
    exit 1
  fi
}

# Configure and build into build/ (programs in build/bin/).
mppi_build() {
  local jobs
  jobs=$(nproc 2>/dev/null || echo 2)
  cmake -S . -B build -DCMAKE_BUILD_TYPE=Release "$@"
  cmake --build build -j"$jobs"
}

if [ "${BASH_SOURCE[0]}" = "$0" ]; then
  cd "$(dirname "$0")/.."
  mppi_setup
fi
