#!/usr/bin/env bash
# Installs every Debian package curvemesh needs to build, test and benchmark.
# Idempotent and non-interactive; run as root on Debian 12.
set -euo pipefail
export DEBIAN_FRONTEND=noninteractive
pkgs=(
  build-essential cmake ninja-build pkg-config clang
  libocct-foundation-dev libocct-modeling-data-dev libocct-modeling-algorithms-dev
  libocct-data-exchange-dev
  libeigen3-dev libtbb-dev libcli11-dev libfmt-dev libspdlog-dev nlohmann-json3-dev
  pybind11-dev libgtest-dev libgmock-dev libbenchmark-dev libgmp-dev
  gmsh python3-gmsh
  occt-misc
)
missing=()
for p in "${pkgs[@]}"; do
  dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed" || missing+=("$p")
done
if ((${#missing[@]})); then
  apt-get update -qq
  apt-get install -y -qq --no-install-recommends "${missing[@]}"
fi
echo "setup: all ${#pkgs[@]} packages present"
