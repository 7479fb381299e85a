#!/usr/bin/env bash
# Installs farfield's build and run dependencies from Debian 12 packages (run as root).
# Quick when everything is already there: apt-get runs only for missing packages.
set -euo pipefail

packages=(
    build-essential cmake ninja-build pkg-config
    libglm-dev libosmesa6-dev mesa-common-dev python3-glad
    libdraco-dev libtinygltf-dev nlohmann-json3-dev libstb-dev
    libopenimageio-dev libxxhash-dev libcli11-dev libmeshoptimizer-dev libabsl-dev
    libglfw3-dev xvfb xauth
    libgtest-dev
    python3-matplotlib time
)

missing=()
for p in "${packages[@]}"; do
    dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed" || missing+=("$p")
done
if [ ${#missing[@]} -gt 0 ]; then
    echo "installing: ${missing[*]}"
    export DEBIAN_FRONTEND=noninteractive
    apt-get update -qq
    apt-get install -y -qq --no-install-recommends "${missing[@]}"
fi
