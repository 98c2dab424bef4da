#!/usr/bin/env bash
# Installs every Debian 12 package drape needs. Idempotent: installs only what is missing.
# Run as root (or with sudo available). Safe to run again.
set -euo pipefail

packages=(
  build-essential cmake pkg-config git python3
  libeigen3-dev libtbb-dev libxsimd-dev
  libglfw3-dev python3-glad libgl-dev libgl1-mesa-dri
  libbenchmark-dev libgtest-dev
  libimgui-dev nlohmann-json3-dev libcli11-dev libstb-dev libtinyobjloader-dev
  xvfb xauth mesa-utils xdotool
  python3-matplotlib
  ffmpeg # the viewer's .mp4 recording (optional at run time; tests/viewer_tools.py checks it when present)
  clang libclang-rt-14-dev
)

missing=()
for p in "${packages[@]}"; do
  if ! dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed"; then
    missing+=("$p")
  fi
done

if ((${#missing[@]} == 0)); then
  echo "setup: all ${#packages[@]} packages present"
  exit 0
fi

echo "setup: installing ${missing[*]}"
SUDO=""
if [ "$(id -u)" != 0 ]; then SUDO="sudo"; fi
export DEBIAN_FRONTEND=noninteractive
$SUDO apt-get update -qq
$SUDO apt-get install -y -qq --no-install-recommends "${missing[@]}" >/dev/null
echo "setup: done"
