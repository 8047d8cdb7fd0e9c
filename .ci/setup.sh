#!/usr/bin/env bash
# Installs every dependency from Debian packages (idempotent), then configures and builds.
set -euo pipefail
cd "$(dirname "$0")/.."
SUDO=""
[ "$(id -u)" -eq 0 ] || SUDO="sudo"
PACKAGES=(
  build-essential cmake pkg-config
  libeigen3-dev libopenmesh-dev libspdlog-dev libcli11-dev doctest-dev
  coinor-libclp-dev libspectra-dev libstb-dev
  libvulkan-dev glslang-tools mesa-vulkan-drivers vulkan-tools
  python3-matplotlib
)
if ! dpkg-query -W -f='${Status}\n' "${PACKAGES[@]}" 2>/dev/null | grep -qv 'install ok installed' \
   && [ "$(dpkg-query -W -f='${Status}\n' "${PACKAGES[@]}" 2>/dev/null | wc -l)" -eq "${#PACKAGES[@]}" ]; then
  echo "setup: all packages present"
else
  $SUDO apt-get update
  DEBIAN_FRONTEND=noninteractive $SUDO apt-get install -y --no-install-recommends "${PACKAGES[@]}"
fi
cmake -S . -B build -DCMAKE_BUILD_TYPE=Release
cmake --build build -j"$(nproc)"
