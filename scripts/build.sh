#!/usr/bin/env bash
# Installs missing packages, then configures and builds a CMake preset (default: release).
#   ./scripts/build.sh [PRESET [TARGET...]]   (no target: everything, tests and benchmarks too)
set -euo pipefail
cd "$(dirname "$0")/.."
preset="${1:-release}"
shift || true
./scripts/setup.sh
cmake --preset "$preset" >/dev/null
if [ "$#" -gt 0 ]; then
  cmake --build --preset "$preset" --target "$@"
else
  cmake --build --preset "$preset"
fi
