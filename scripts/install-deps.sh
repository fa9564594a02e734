#!/usr/bin/env bash
# Installs every Debian 12 package aarad needs to build, test and benchmark.
# The one place that names apt packages; `make demo` and `make test` call it.
set -euo pipefail

packages=(
  build-essential cmake pkg-config
  libglm-dev libcgal-dev libgmp-dev libmpfr-dev libboost-dev
  libopenmesh-dev libopenimageio-dev libtinyobjloader-dev
  libtbb-dev libcli11-dev nlohmann-json3-dev
  libgtest-dev libgmock-dev libbenchmark-dev
  libfreetype-dev libstb-dev libagg-dev
)

missing=()
for p in "${packages[@]}"; do
  dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed" || missing+=("$p")
done
[ ${#missing[@]} -eq 0 ] && exit 0

echo "aarad: installing missing packages: ${missing[*]}"
sudo_cmd=()
[ "$(id -u)" -ne 0 ] && sudo_cmd=(sudo)
export DEBIAN_FRONTEND=noninteractive
"${sudo_cmd[@]}" apt-get update -qq
"${sudo_cmd[@]}" apt-get install -y -qq --no-install-recommends "${missing[@]}"
