#!/usr/bin/env bash
# Installs every Debian package sirl-bench needs, skipping what is already present.
# Idempotent: running it twice installs nothing the second time. Needs root (or sudo) only
# when something is missing. --tests adds what only the test suite needs: a one-node Slurm
# (slurmctld, slurmd, munge; the Slurm test starts and stops its own daemons in a temporary
# folder, with its own config and key). --list prints the packages (one per line, with --tests'
# too if given first) and installs nothing: the list to hand a cluster's administrators.
set -euo pipefail

packages=(
  # build
  build-essential cmake ninja-build pkg-config ccache git
  # engine dependencies
  libeigen3-dev libtbb-dev libhdf5-dev libsuitesparse-dev libmujoco-dev
  libcli11-dev libtomlplusplus-dev libfmt-dev nlohmann-json3-dev
  libxxhash-dev xxhash  # XXH3-128 checksums (the library; xxh128sum checks a .sum by hand)
  libbenchmark-dev libgtest-dev libgmock-dev
  # the GEMM libraries bench/bench_gemm_candidates.cpp measures against our kernels
  libdnnl-dev libxsmm-dev
  # oneDNN's CMake config looks for OpenCL (a Recommends of libdnnl-dev, which we skip)
  ocl-icd-opencl-dev
  # sanitizer builds and the libFuzzer targets (the asan/tsan presets)
  clang libclang-rt-dev libomp-dev
  # MPI scale-out
  libopenmpi-dev openmpi-bin
  # plots and the PyTorch reference (Debian's /usr/bin/python3 only)
  python3 python3-h5py python3-matplotlib python3-numpy python3-pandas python3-scipy python3-torch
  python3-markdown  # report.html's tables
  python3-xxhash    # the Python reader verifies results files' XXH3-128 checksums
  python3-xarray    # optional: sirl_bench's to_xarray() (tested when present)
  libopenblas0-pthread
  # the user study: web server, browser-side packages from npm, the browser for its e2e test
  libcpp-httplib-dev nodejs chromium
)
if [ "${1:-}" = "--tests" ]; then
  packages+=(slurmctld slurmd slurm-client munge)
  shift
fi
if [ "${1:-}" = "--list" ]; then
  printf '%s\n' "${packages[@]}" npm
  exit 0
fi

missing=()
for p in "${packages[@]}"; do
  if ! dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed"; then
    missing+=("$p")
  fi
done

# three.js (the study page's 3-D views) and playwright-core (its browser test) from the npm
# registry, pinned by app/study_web/package-lock.json; reinstalled only when the lock changes.
npm_install() {
  local web
  web="$(cd "$(dirname "$0")/.." && pwd)/app/study_web"
  if [ ! -f "$web/node_modules/.package-lock.json" ] ||
     ! cmp -s "$web/package-lock.json" "$web/node_modules/.sirl-lock"; then
    echo "setup: npm ci in app/study_web"
    (cd "$web" && npm ci --no-audit --no-fund --loglevel=error && cp package-lock.json node_modules/.sirl-lock)
  fi
}

# Debian's nodejs needs the separate npm package; NodeSource's nodejs bundles npm and conflicts
# with it. Ask for the package only when no npm command exists.
if ! command -v npm >/dev/null 2>&1 && [[ ! " ${missing[*]} " =~ " npm " ]]; then
  missing+=(npm)
fi

# The results reader (python/sirl_bench) on the path of Debian's /usr/bin/python3: a .pth file
# in the user's site-packages naming this checkout's python/ folder (no network, no pip). Rewritten
# only when it names another folder.
python_reader() {
  local site pth want
  want="$(cd "$(dirname "$0")/.." && pwd)/python"
  site="$(/usr/bin/python3 -c 'import site; print(site.getusersitepackages())')"
  pth="$site/sirl_bench.pth"
  if [ "$(cat "$pth" 2>/dev/null)" != "$want" ]; then
    mkdir -p "$site" && printf '%s\n' "$want" > "$pth"
    echo "setup: sirl_bench reader → $pth"
  fi
}

if [ ${#missing[@]} -eq 0 ]; then
  echo "setup: all ${#packages[@]} packages present"
  npm_install
  python_reader
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
npm_install
python_reader
echo "setup: done"
