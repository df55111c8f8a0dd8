#!/usr/bin/env bash
# Installs every Debian package zeroset needs that is missing; does nothing when all are there.
# Usage: scripts/install-deps.sh [--peers]   (--peers adds the tools the benchmarks compare against)
set -euo pipefail

build=(cmake g++ make pkg-config clang libclang-rt-14-dev dpkg-dev
       zlib1g-dev libeigen3-dev libcli11-dev libfmt-dev nlohmann-json3-dev libstb-dev libomp-dev
       libgtest-dev libgmock-dev libbenchmark-dev
       libglfw3-dev libepoxy-dev libimgui-dev
       xvfb xauth libgl1-mesa-dri povray
       pybind11-dev python3-dev python3-pytest python3-numpy python3-setuptools python3-pip
       python3-venv)
peers=(surf-alggeo-nox python3-vtk9 python3-skimage python3-numpy libcgal-dev ffmpeg hyperfine)

want=("${build[@]}")
if [[ "${1:-}" == "--peers" ]]; then want+=("${peers[@]}"); fi

missing=()
for p in "${want[@]}"; do
  dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed" || missing+=("$p")
done
if ((${#missing[@]} == 0)); then
  echo "install-deps: all ${#want[@]} packages present"
  exit 0
fi
echo "install-deps: installing ${missing[*]}"
sudo=""
if [[ $(id -u) -ne 0 ]]; then sudo="sudo"; fi
export DEBIAN_FRONTEND=noninteractive
$sudo apt-get update -qq
$sudo apt-get install -y -qq --no-install-recommends "${missing[@]}"
