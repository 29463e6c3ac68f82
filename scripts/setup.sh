#!/usr/bin/env bash
# Installs every Debian package sirl-bench needs, skipping what is already present.
# Idempotent: running it twice installs nothing the second time. Needs root (or sudo) only
# when something is missing.
set -euo pipefail

packages=(
  # build
  build-essential cmake ninja-build pkg-config ccache git
  # engine dependencies
  libeigen3-dev libtbb-dev libhdf5-dev libsuitesparse-dev libmujoco-dev
  libcli11-dev libtomlplusplus-dev libfmt-dev
  libbenchmark-dev libgtest-dev libgmock-dev
  # MPI scale-out
  libopenmpi-dev openmpi-bin
  # plots and the PyTorch reference (Debian's /usr/bin/python3 only)
  python3 python3-h5py python3-matplotlib python3-numpy python3-pandas python3-scipy python3-torch
  libopenblas0-pthread
)

missing=()
for p in "${packages[@]}"; do
  if ! dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed"; then
    missing+=("$p")
  fi
done

if [ ${#missing[@]} -eq 0 ]; then
  echo "setup: all ${#packages[@]} packages present"
  exit 0
fi

echo "setup: installing ${#missing[@]} missing packages: ${missing[*]}"
sudo=""
if [ "$(id -u)" -ne 0 ]; then
  command -v sudo >/dev/null || { echo "setup: need root (or sudo) to install: ${missing[*]}" >&2; exit 1; }
  sudo="sudo"
fi
export DEBIAN_FRONTEND=noninteractive
$sudo apt-get update -qq
$sudo apt-get install -y -qq --no-install-recommends "${missing[@]}"
echo "setup: done"
